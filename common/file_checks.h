#pragma once

#include <filesystem>
#include <system_error>

namespace canopy {

// Whether `path` names a regular file / anything, without throwing: a path from a user's file can
// be too long or unreadable, and that is a "not found" for the message, not a filesystem_error.
inline bool regularFileExists(const std::filesystem::path& path) noexcept {
  std::error_code ignored;
  return std::filesystem::is_regular_file(path, ignored);
}
inline bool pathExists(const std::filesystem::path& path) noexcept {
  std::error_code ignored;
  return std::filesystem::exists(path, ignored);
}

}  // namespace canopy
