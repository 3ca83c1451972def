#pragma once

#include <filesystem>
#include <functional>
#include <string_view>

namespace canopy {

// Writes `path` through `writer`, which fills a temporary file beside it; the temporary is then
// fsynced and renamed over `path`, so a reader (or an interrupted run) sees the old file or the
// new one, never half of one.
void writeFileAtomically(const std::filesystem::path& path,
                         const std::function<void(const std::filesystem::path&)>& writer);

// Replaces `path` with `text` atomically.
void writeTextAtomically(const std::filesystem::path& path, std::string_view text);

// Appends one line (a JSON record) so that a crash leaves either the whole line or none of it:
// the line is written with a single O_APPEND write and fsynced. A torn last line left by a kill
// during the write is detected by the reader (no trailing newline) and dropped.
void appendLineDurably(const std::filesystem::path& path, std::string_view line);

}  // namespace canopy
