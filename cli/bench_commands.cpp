// dynsky bench sampling: the sky importance-sampling study (bench/sampling_study.h).
#include <memory>

#include "bench/sampling_study.h"
#include "cli/commands.h"
#include "cli/options.h"
#include "renderer/sky_sampler.h"

namespace dynsky::cli {

void register_bench_commands(CLI::App& app) {
    CLI::App* bench = app.add_subcommand("bench", "Benchmarks that write reports");
    bench->require_subcommand(1);
    auto o = std::make_shared<SamplingStudyOptions>();
    CLI::App* s = bench->add_subcommand("sampling",
                                        "Sky importance sampling: accuracy vs time, rebuild cost, failure cases; "
                                        "writes README.md, CSV files and PNG charts into --out");
    s->add_flag(
        "--quick", o->quick,
        "Small: 32x24 images, 256 px skies, 384-spp references, 1/4/16 spp, depth 3 (CI; about 30 s). Without it: "
        "160x120, 1024 px skies, 4096-spp references, 1-64 spp, depth 5; everything at 4 seeds takes over an hour "
        "on 2 cores, so pick with --skies, --scenes, --samplers and --parts (docs/sampling/README.md lists the runs)");
    s->add_option("--out,-o", o->out, "Report folder (created)")->capture_default_str();
    s->add_option("--cache", o->cache, "Folder for cached reference renders (default: OUT/cache)");
    s->add_option("--shared", o->shared, "The shared data folder (scenes, photographs)")->capture_default_str();
    s->add_option("--seeds", o->seeds,
                  "Renders per point with different seeds (error bars; default 2 with --quick, else 4)")
        ->check(CLI::Range(1, 64));
    s->add_option("--skies", o->skies, "Only these skies: clear, cumulus, overcast, photo (default all)")
        ->delimiter(',')
        ->check(CLI::IsMember({"clear", "cumulus", "overcast", "photo"}));
    s->add_option("--scenes", o->scenes, "Only these scenes: diffuse, glossy, plaza, house (default all)")
        ->delimiter(',')
        ->check(CLI::IsMember({"diffuse", "glossy", "plaza", "house"}));
    s->add_option("--samplers", o->samplers,
                  "Only these samplers, e.g. cdf,cdf+mis,alias+mis (default all; "
                  "plain cdf is the baseline of every speed-up)")
        ->delimiter(',')
        ->check(parsed_by([](const std::string& s) { parse_sky_sampler(s); }, "SAMPLER"));
    s->add_option("--parts", o->parts, "Only these parts: accuracy, rebuild, failures (default all)")
        ->delimiter(',')
        ->check(CLI::IsMember({"accuracy", "rebuild", "failures"}));
    s->callback([o] { run_sampling_study(*o); });
}

}  // namespace dynsky::cli
