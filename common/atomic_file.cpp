#include "common/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>

#include "common/error.h"

namespace canopy {
namespace {

void fsyncPath(const std::filesystem::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

}  // namespace

void writeFileAtomically(const std::filesystem::path& path,
                         const std::function<void(const std::filesystem::path&)>& writer) {
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  std::filesystem::path temporary = path;
  temporary += ".tmp." + std::to_string(::getpid());
  try {
    writer(temporary);
    fsyncPath(temporary);
    std::filesystem::rename(temporary, path);
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw;
  }
}

void writeTextAtomically(const std::filesystem::path& path, std::string_view text) {
  writeFileAtomically(path, [&](const std::filesystem::path& temporary) {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    if (!out) throwInputError("{}: cannot write ({})", path.string(), std::strerror(errno));
  });
}

void appendLineDurably(const std::filesystem::path& path, std::string_view line) {
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  std::string buffer(line);
  buffer.push_back('\n');
  const int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CREAT, 0644);
  if (fd < 0)
    throwInputError("{}: cannot open for appending ({})", path.string(), std::strerror(errno));
  const ssize_t written = ::write(fd, buffer.data(), buffer.size());
  const int writeErrno = errno;
  ::fsync(fd);
  ::close(fd);
  if (written != static_cast<ssize_t>(buffer.size())) {
    throwInputError("{}: short append ({})", path.string(), std::strerror(writeErrno));
  }
}

}  // namespace canopy
