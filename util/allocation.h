// Process-wide allocation policy for the per-frame sky work.
#pragma once

namespace dynsky {

// Keeps freed large blocks in the process instead of returning them to the system (glibc's
// mallopt: mmap threshold 256 MB, trim threshold 1 GB). Every medium step and frame makes and
// frees full-sky temporaries (12 MB each at 1024 px); handed back to the kernel, each one
// page-faults in again on the next step: a 1024 px advect-residual step took 2.9x the CPU time
// (bench/cloud_model_bench AdvectResidualSkyStep/1024/1: 665 vs 228 ms). Idempotent; a no-op
// off glibc.
void keep_large_allocations();

}  // namespace dynsky
