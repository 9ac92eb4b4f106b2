// The main of the Google Benchmark programs: runs the benchmarks selected on the command line and
// exits 1 when any of them reported an error (its data missing: ../shared, a model), saying how
// many. Google Benchmark itself exits 0, so a script got no ratio and no failure.
#pragma once

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <vector>

namespace dynsky::bench {

// The console reporter, counting the runs that reported an error.
class ErrorCountingReporter : public benchmark::ConsoleReporter {
  public:
    // Coloured on a terminal only, as Google Benchmark's own (--benchmark_color=auto).
    ErrorCountingReporter() : ConsoleReporter(isatty(STDOUT_FILENO) ? OO_Defaults : OO_Tabular) {}
    void ReportRuns(const std::vector<Run>& runs) override {
        for (const Run& run : runs) errors += run.error_occurred ? 1 : 0;
        ConsoleReporter::ReportRuns(runs);
    }
    int errors = 0;
};

inline int run_benchmarks(int argc, char** argv) {
    // Another display format asked for (--benchmark_format=json|csv) is Google Benchmark's own.
    bool console = true;
    for (int i = 1; i < argc; ++i)
        if (std::strncmp(argv[i], "--benchmark_format=", 19) == 0 && std::strcmp(argv[i] + 19, "console") != 0)
            console = false;
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    ErrorCountingReporter reporter;
    if (console) benchmark::RunSpecifiedBenchmarks(&reporter);
    else benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    if (reporter.errors > 0) {
        std::fprintf(stderr, "%d benchmark run(s) reported an error (above): their figures are missing\n",
                     reporter.errors);
        return 1;
    }
    return 0;
}

}  // namespace dynsky::bench
