// Errors that reach the user: each names the file (or input) and the problem.
#pragma once

#include <stdexcept>
#include <string>

namespace dynsky {

class Error : public std::runtime_error {
  public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// "PATH: problem", the form every input error takes.
[[noreturn]] inline void throw_file_error(const std::string& path, const std::string& problem) {
    throw Error(path + ": " + problem);
}

}  // namespace dynsky
