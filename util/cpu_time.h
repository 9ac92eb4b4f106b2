#pragma once

namespace dynsky {

// CPU seconds this process has used, all threads together (CLOCK_PROCESS_CPUTIME_ID): a cost that
// other processes sharing the machine do not inflate, unlike wall-clock time.
double process_cpu_seconds();

}  // namespace dynsky
