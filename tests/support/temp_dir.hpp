#pragma once
// Temporary directories for the tests that write state files, stores and firmware slots.
#include <stdlib.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>

namespace test_support {

// A new, empty directory "<prefix>XXXXXX" (made unique by mkdtemp) under the system temporary directory.
// The caller removes it; throws if it cannot be created.
inline std::filesystem::path make_temp_dir(const std::string& prefix = "softecat-test-") {
    std::string pattern = (std::filesystem::temp_directory_path() / (prefix + "XXXXXX")).string();
    if (::mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp " + pattern);
    return pattern;
}

// A fresh directory, removed with everything in it when the object goes.
struct TempDir {
    std::filesystem::path path;
    explicit TempDir(const std::string& prefix = "softecat-test-") : path(make_temp_dir(prefix)) {}
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
};

}  // namespace test_support
