// Probe for the layering check (tests/CMakeLists.txt, test LayeringUpwardIncludeFails):
// compiled with the include roots of the structures layer (raylab_accel), an
// include of the tracer, a higher layer, must not resolve.
#include "accel/accelerator.h"
#include "tracer/camera.h"

int raylab_layering_probe_upward() { return 0; }
