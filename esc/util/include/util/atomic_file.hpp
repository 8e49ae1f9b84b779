#pragma once
// Crash-safe replacement of a file: the bytes go to "<file>.tmp", which is fsync'ed, renamed onto the file
// and the directory fsync'ed, so after a crash at any point the file holds either the old or the new
// content in full (a stale .tmp may remain; remove_stale_temp() drops it).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <string_view>

namespace util {

// Called after each durable step: "temp-written", "renamed", "done" (tests simulate a crash there).
using AtomicWriteStep = std::function<void(std::string_view step)>;

// Writes bytes to file atomically (creating the parent directory if needed). Returns "" on success or a
// readable error ("cannot write <path>: <strerror>"); on an error before the rename the old file is kept.
std::string write_file_atomic(const std::filesystem::path& file, std::span<const uint8_t> bytes,
                              const AtomicWriteStep& on_step = {});

// fsync of a directory (makes a rename or unlink in it durable). False with errno set on failure.
bool sync_directory(const std::filesystem::path& dir);

// Removes "<file>.tmp" left by an interrupted write. True if there was one.
bool remove_stale_temp(const std::filesystem::path& file);

// "<what> <path>: <strerror(errno)>".
std::string errno_text(std::string_view what, const std::filesystem::path& path);

}  // namespace util
