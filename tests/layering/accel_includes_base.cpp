// Control for the layering check: the same probe target setup, including only
// the structures layer and the base below it, builds. So the failure of
// accel_includes_tracer.cpp is the upward include and nothing else.
#include "accel/accelerator.h"
#include "base/pcg.h"

int raylab_layering_probe_downward() { return 0; }
