#include "cli/exit_codes.h"

#include <cctype>
#include <cstdio>
#include <regex>
#include <string>
#include <vector>

#include "util/suggest.h"

namespace dynsky::cli {

std::string exit_codes_help() {
    return "Exit codes: 0 done; 1 runtime error (an input missing, unreadable or bad, an output not written);\n"
           "2 usage error (unknown command or option, bad option value); 3 interrupted (the file being written\n"
           "removed). See docs/exit-codes.md.";
}

int exit_code_of(const Error& e) { return std::string(e.what()).rfind("--", 0) == 0 ? kUsageError : kRuntimeError; }

namespace {

std::vector<std::string> command_names(const CLI::App* app) {
    std::vector<std::string> names;
    for (const CLI::App* sub : app->get_subcommands([](const CLI::App*) { return true; }))
        if (!sub->get_name().empty()) names.push_back(sub->get_name());
    return names;
}

std::vector<std::string> option_names(const CLI::App* app) {
    std::vector<std::string> names;
    for (const CLI::Option* opt : app->get_options())
        for (const std::string& n : opt->get_lnames()) names.push_back("--" + n);
    return names;
}

std::string join(const std::vector<std::string>& names) {
    std::string s;
    for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
    return s;
}

// The subcommand of cmd called word, or null.
CLI::App* subcommand_named(CLI::App* cmd, const std::string& word) {
    for (CLI::App* sub : cmd->get_subcommands([](const CLI::App*) { return true; }))
        if (sub->check_name(word)) return sub;
    return nullptr;
}

// "dynsky sky" for the command a word belongs to.
std::string command_path(const CLI::App* app) {
    std::string s;
    // The root's own name is the program's path as typed (argv[0]): "dynsky" stands for it.
    for (; app && app->get_parent(); app = app->get_parent())
        s = app->get_name().empty() ? s : app->get_name() + (s.empty() ? "" : " " + s);
    return "dynsky" + (s.empty() ? "" : " " + s);
}

// Walks the words as the parser did: into subcommands by name; the first word that is no command
// where a command is expected, or an option the command lacks, gets a suggestion.
std::string suggestion(CLI::App& app, int argc, char** argv) {
    CLI::App* cmd = &app;
    for (int i = 1; i < argc; ++i) {
        std::string word = argv[i];
        if (word == "--") break;
        if (word.size() > 2 && word.rfind("--", 0) == 0) {
            std::string name = word.substr(0, word.find('='));
            if (cmd->get_option_no_throw(name) != nullptr || name == "--help" || name == "--help-all") continue;
            std::string best = closest_name(name, option_names(cmd));
            return command_path(cmd) + " has no option " + name + (best.empty() ? "" : "; did you mean " + best + "?");
        }
        if (word[0] == '-') continue;
        std::vector<std::string> commands = command_names(cmd);
        if (commands.empty()) continue;  // a value or a positional argument of a leaf command
        if (CLI::App* sub = subcommand_named(cmd, word)) {
            cmd = sub;
            continue;
        }
        std::string best = closest_name(word, commands);
        return "'" + word + "' is not a command of " + command_path(cmd) +
               (best.empty() ? "" : "; did you mean '" + best + "'?") + " Commands: " + join(commands);
    }
    if (!command_names(cmd).empty() && cmd->get_subcommands().empty())
        return command_path(cmd) + " needs a command: " + join(command_names(cmd));
    return "";
}

}  // namespace

bool print_help_if_asked(CLI::App& app, int argc, char** argv) {
    CLI::App* cmd = &app;
    for (int i = 1; i < argc; ++i) {
        const std::string word = argv[i];
        if (word == "--") break;
        if (word == "-h" || word == "--help" || word == "--help-all") {
            // The command the words before it named; usage names it as typed: "dynsky sky clear".
            const auto mode = word == "--help-all" ? CLI::AppFormatMode::All : CLI::AppFormatMode::Normal;
            if (cmd->get_parent() == nullptr) cmd->name("dynsky");
            std::fputs(cmd->help(cmd->get_parent() ? command_path(cmd->get_parent()) : "", mode).c_str(), stdout);
            return true;
        }
        if (CLI::App* sub = subcommand_named(cmd, word)) cmd = sub;
    }
    return false;
}

std::string missing_option_value(CLI::App& app, int argc, char** argv) {
    CLI::App* cmd = &app;
    for (int i = 1; i < argc; ++i) {
        const std::string word = argv[i];
        if (word == "--") break;
        if (word.empty()) continue;
        if (word[0] != '-') {
            if (CLI::App* sub = subcommand_named(cmd, word)) cmd = sub;
            continue;
        }
        if (word.find('=') != std::string::npos || i + 1 >= argc) continue;
        const CLI::Option* opt = cmd->get_option_no_throw(word);
        if (opt == nullptr || opt->get_expected_min() == 0) continue;  // unknown (said by the parse), a flag
        const std::string next = argv[i + 1];
        // A negative number is a value; another option's name (or anything spelt like one) is not.
        const bool is_option = next.rfind("--", 0) == 0 ||
                               (next.size() == 2 && next[0] == '-' && std::isalpha((unsigned char)next[1]));
        if (is_option) return word + ": its value is missing (the next word, " + next + ", is an option)";
    }
    return "";
}

std::string plain_parse_message(const std::string& message) {
    std::smatch m;
    // CLI11: "Could not convert: --steps = 1e308" (a value its type cannot hold or read).
    if (std::regex_match(message, m, std::regex("Could not convert: (-[^ ]+) = (.*)")))
        return m[1].str() + ": '" + m[2].str() + "' is not a value of this option (a number in its range)";
    // CLI11: "--res: At Most 1 required but received 2" (an option given twice).
    if (std::regex_match(message, m, std::regex("(-[^:]+): At Most 1 required but received ([0-9]+)")))
        return m[1].str() + ": given " + m[2].str() + " times; give it once";
    // CLI11: "--threads: Value abc not in range 0 to 4096" (a Range check on a word).
    if (std::regex_match(message, m, std::regex("(-[^:]+): Value (.*) not in range (.*) to (.*)")))
        return m[1].str() + ": '" + m[2].str() + "' is not a number in " + m[3].str() + " .. " + m[4].str();
    return message;
}

// The first option given on the command line that --help leaves out (an old spelling kept
// working: add_hidden_alias), "" if none. CLI11 names a hidden option "" in its errors.
std::string hidden_option_given(CLI::App& app, int argc, char** argv) {
    CLI::App* cmd = &app;
    for (int i = 1; i < argc; ++i) {
        std::string word = argv[i];
        if (word == "--") break;
        if (word.empty()) continue;
        if (word[0] != '-') {
            if (CLI::App* sub = subcommand_named(cmd, word)) cmd = sub;
            continue;
        }
        word = word.substr(0, word.find('='));
        const CLI::Option* opt = cmd->get_option_no_throw(word);
        if (opt != nullptr && opt->get_group().empty()) return word;
    }
    return "";
}

int report_parse_error(CLI::App& app, const CLI::ParseError& e, int argc, char** argv) {
    if (e.get_exit_code() == int(CLI::ExitCodes::Success)) return app.exit(e);  // --help, --help-all
    std::string hint = suggestion(app, argc, argv);
    // CLI11's error of a hidden option begins ": ..." (its name left out): named here.
    if (hint.empty() && std::string(e.what()).rfind(": ", 0) == 0)
        if (const std::string name = hidden_option_given(app, argc, argv); !name.empty())
            hint = name + std::string(e.what());
    // The hint names what is wrong ("'rendr' is not a command ...; did you mean 'render'?"), where
    // CLI11's own line said "A subcommand is required": the hint alone then.
    std::fprintf(stderr, "dynsky: usage error: %s\n",
                 hint.empty() ? plain_parse_message(e.what()).c_str() : hint.c_str());
    std::fprintf(stderr, "Run with --help for more information.\n");
    return kUsageError;
}

}  // namespace dynsky::cli
