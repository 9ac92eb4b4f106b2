// dynsky: moving HDR skies and the scenes they light. One program, subcommands.
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <functional>
#include <iostream>
#include <new>
#include <string>

#include <opencv2/core.hpp>

#include "cli/commands.h"
#include "cli/exit_codes.h"
#include "cli/options.h"
#include "util/atomic_file.h"
#include "util/interrupt.h"
#include "util/child_process.h"
#include "util/error.h"
#include "util/progress.h"
#include "util/version.h"

namespace {

// Out of memory: what the command was asked to hold, so the message says what to make smaller. The
// command's input files with their sizes (a scene, a sky, photographs), and the options that size
// its images.
void out_of_memory(int argc, char** argv) {
    std::string command = argc > 1 ? argv[1] : "dynsky", inputs;
    if (argc > 2 && (command == "sky" || command == "bench") && argv[2][0] != '-')
        command += std::string(" ") + argv[2];
    for (int i = 2; i < argc; ++i) {
        std::error_code ec;
        const std::string word = argv[i];
        if (word.empty() || word[0] == '-' || !std::filesystem::is_regular_file(word, ec)) continue;
        const auto bytes = std::filesystem::file_size(word, ec);
        if (ec) continue;
        char size[32];
        std::snprintf(size, sizeof size, " (%.3g MB)", double(bytes) / 1e6);
        inputs += (inputs.empty() ? "" : ", ") + word + size;
    }
    std::fprintf(stderr,
                 "dynsky: error: out of memory in '%s': what it was asked for does not fit in the memory this "
                 "process may use (the machine's, or a limit: ulimit -v, a container's)%s%s; ask for less: "
                 "smaller images (--res, --sky-res, --width), a smaller scene or sky file, fewer textures\n",
                 command.c_str(), inputs.empty() ? "" : "; its inputs: ", inputs.c_str());
}

// SIGINT/SIGTERM/SIGHUP: remove the output being written (nothing half-written stays; an animation's
// frames written so far are kept and resume) and exit with kInterrupted. Where work can stop at a
// clean point (util/interrupt.h: a render between rounds of samples) the first one asks it to, and
// the program writes what it has and exits with kInterrupted; the second stops at once.
extern "C" void on_interrupt(int) {
    if (dynsky::graceful_stop_allowed() && !dynsky::request_stop()) {
        const char head[] = "\ndynsky: interrupted: ", tail[] = " (interrupt again to stop at once, writing nothing)\n";
        const char* action = dynsky::graceful_stop_action();
        ssize_t ignored = ::write(2, head, sizeof head - 1);
        ignored = ::write(2, action, std::strlen(action));  // async-signal-safe (POSIX.1-2017)
        ignored = ::write(2, tail, sizeof tail - 1);
        (void)ignored;
        return;
    }
    dynsky::stop_active_child();  // ffmpeg, writing the temporary removed next
    dynsky::remove_active_temporary();
    const char message[] = "dynsky: interrupted\n";
    ssize_t ignored = ::write(2, message, sizeof message - 1);
    (void)ignored;
    ::_exit(dynsky::cli::kInterrupted);
}

void install_signal_handlers() {
    // A file size limit (ulimit -f) then fails the write with EFBIG, reported naming the file,
    // instead of killing the process with a half-written temporary.
    ::signal(SIGXFSZ, SIG_IGN);
    struct sigaction sa;
    std::memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_interrupt;
    sigemptyset(&sa.sa_mask);
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(sig, &sa, nullptr);
}

int run(int argc, char** argv) {
    install_signal_handlers();
    CLI::App app{
        "dynsky: time-varying HDR skies (clear, photographed, procedural, with moving clouds) and a\n"
        "CPU path tracer that renders glTF 2.0 scenes under them.\n"
        "Sky images are equidistant fisheye EXRs of the upper hemisphere, north up, east left."};
    app.require_subcommand(1);
    app.set_help_all_flag("--help-all", "Show help for every subcommand");
    app.set_version_flag("--version", dynsky::dynsky_version());
    app.footer(dynsky::cli::exit_codes_help());

    dynsky::cli::register_render_command(app);
    CLI::App* sky = app.add_subcommand("sky", "Make, import, convert and inspect sky images");
    sky->require_subcommand(1);
    dynsky::cli::register_sky_clear_commands(*sky);
    dynsky::cli::register_sky_import_commands(*sky);
    dynsky::cli::register_sky_procedural_command(*sky);
    dynsky::cli::register_sky_model_commands(*sky);
    dynsky::cli::register_sky_timeline_command(*sky);
    dynsky::cli::register_bench_commands(app);
    dynsky::cli::register_animate_command(app);
    dynsky::cli::register_compare_command(app);
    // The same -q,--quiet on every command (those without their own silence stdout).
    std::function<void(CLI::App*)> add_quiet = [&](CLI::App* cmd) {
        auto subs = cmd->get_subcommands({});
        for (CLI::App* sub : subs) add_quiet(sub);
        if (subs.empty() && cmd->get_option_no_throw("--quiet") == nullptr) dynsky::cli::add_quiet_flag(cmd);
    };
    add_quiet(&app);

    // An empty value ("--time-limit ''", "--spp=") is never meant, and CLI11 reads one as 0 or the
    // default for the options without a range check: refused for every option alike.
    for (int i = 1; i < argc; ++i) {
        const std::string word = argv[i], before = i > 1 ? argv[i - 1] : "";
        if (word == "--") break;
        std::string option;
        if (word.size() > 3 && word.rfind("--", 0) == 0 && word.back() == '=') option = word.substr(0, word.size() - 1);
        else if (word.empty() && before.size() > 2 && before.rfind("--", 0) == 0 &&
                 before.find('=') == std::string::npos)
            option = before;
        if (option.empty()) continue;
        std::fprintf(stderr, "dynsky: usage error: %s: an empty value (give one, or leave the option out)\n",
                     option.c_str());
        return dynsky::cli::kUsageError;
    }
    if (dynsky::cli::print_help_if_asked(app, argc, argv)) return 0;
    if (const std::string missing = dynsky::cli::missing_option_value(app, argc, argv); !missing.empty()) {
        std::fprintf(stderr, "dynsky: usage error: %s\n", missing.c_str());
        return dynsky::cli::kUsageError;
    }
    // -q silences the libraries' reports and progress too (notes, bars, "wrote ..."), for the
    // commands with their own --quiet as for the others.
    for (int i = 1; i < argc; ++i)
        if (std::string(argv[i]) == "-q" || std::string(argv[i]) == "--quiet") dynsky::silence_reports(true);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return dynsky::cli::report_parse_error(app, e, argc, argv);
    } catch (const dynsky::Error& e) {
        // An option's error ("--wind: ...") is a usage error, said as CLI11's own are.
        const int code = dynsky::cli::exit_code_of(e);
        std::fprintf(stderr, "dynsky: %s: %s\n", code == dynsky::cli::kUsageError ? "usage error" : "error", e.what());
        return code;
    } catch (const std::bad_alloc&) {
        out_of_memory(argc, argv);
        return dynsky::cli::kRuntimeError;
    } catch (const cv::Exception& e) {
        // OpenCV's allocations fail with its own exception, not bad_alloc: its raw text named no
        // input and no option.
        if (e.code == cv::Error::StsNoMem) out_of_memory(argc, argv);
        else std::fprintf(stderr, "dynsky: error: OpenCV failed: %s\n", e.err.c_str());
        return dynsky::cli::kRuntimeError;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "dynsky: error: %s\n", e.what());
        return dynsky::cli::kRuntimeError;
    }
    // Stopped early at a clean point, with what it had written (a render's image of fewer samples).
    if (dynsky::stopped_early()) return dynsky::cli::kInterrupted;
    return dynsky::cli::kSuccess;
}

// What a command printed must have arrived: `$(dynsky animate --count-frames)` into a full disk or
// a closed stdout read an empty string with exit 0.
int checked_standard_output(int code) {
    std::cout.flush();
    errno = 0;
    const bool failed = std::fflush(stdout) != 0 || std::ferror(stdout) || std::cout.fail();
    if (!failed) return code;
    const int err = errno;
    std::fprintf(stderr, "dynsky: error: standard output: %s: what the command printed did not all arrive\n",
                 err ? std::strerror(err) : "could not be written (closed, or a full disk)");
    return code == dynsky::cli::kSuccess ? dynsky::cli::kRuntimeError : code;
}

}  // namespace

int main(int argc, char** argv) { return checked_standard_output(run(argc, argv)); }
