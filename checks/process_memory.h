#pragma once
// Memory as the OS sees it: this process's resident set (now and its peak) and
// what the machine or the job's cgroup can still give. `raylab bench` records
// the peak per structure; the memory guard (checks/memory_guard.h) compares
// each step's estimate with what is available before the step runs.
#include <cstddef>

namespace raylab {

// Linux /proc/self/status VmRSS and VmHWM in bytes (0 where unavailable).
size_t resident_bytes();
size_t peak_resident_bytes();

// Restarts the peak (VmHWM) at the current resident set (writes "5" to
// /proc/self/clear_refs, Linux 4.0+), so the next peak_resident_bytes() is
// the peak of what runs in between. False where not supported: the peak then
// stays the process's peak since it started.
bool reset_peak_resident();

// Bytes the process can still allocate without swapping or hitting a limit:
// the smaller of MemAvailable (/proc/meminfo) and the room left under the
// cgroup v2 memory.max of this process (a Slurm job's allocation, a container).
size_t available_memory_bytes();

// MemAvailable alone (no cgroup limit); 0 where unavailable.
size_t mem_available_bytes();

}  // namespace raylab
