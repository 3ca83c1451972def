#pragma once

#include <cstdio>

#include <filesystem>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

namespace canopy {

// Bad user input (a file, a config key, a parameter): caught once in each main, which prints the
// message on one line and exits with code 2. The message must name the file or key.
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

template <typename... Args>
[[noreturn]] void throwInputError(fmt::format_string<Args...> format, Args&&... args) {
  throw InputError(fmt::format(format, std::forward<Args>(args)...));
}

// Exit codes shared by every executable (DESIGN.md contract).
inline constexpr int kExitOk = 0;
inline constexpr int kExitInternalError = 1;
inline constexpr int kExitBadInput = 2;

// Runs a program's body (returning its exit code) under the contract: an InputError becomes one
// line "<program>: <message>" on stderr and exit code 2, as does a filesystem error (a folder
// that cannot be created, a file that cannot be moved: the user's disk, named by its path); any
// other exception is "internal error" and 1.
template <typename Body>
int runWithExitCodes(const char* program, Body&& body) {
  try {
    return body();
  } catch (const InputError& error) {
    std::fprintf(stderr, "%s: %s\n", program, error.what());
    return kExitBadInput;
  } catch (const std::filesystem::filesystem_error& error) {
    std::fprintf(stderr, "%s: %s: %s\n", program,
                 error.path1().empty() ? "(file system)" : error.path1().c_str(),
                 error.code().message().c_str());
    return kExitBadInput;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "%s: internal error: %s\n", program, error.what());
    return kExitInternalError;
  }
}

}  // namespace canopy
