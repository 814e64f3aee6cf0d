// Probe for the layering check (tests/CMakeLists.txt, test LayeringSiblingIncludeFails):
// compiled with the include roots of the structures layer (raylab_accel), an
// include of the scenes layer, its sibling (neither includes the other), must
// not resolve.
#include "accel/accelerator.h"
#include "scenes/scene.h"

int raylab_layering_probe_sibling() { return 0; }
