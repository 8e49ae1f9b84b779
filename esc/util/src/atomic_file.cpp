#include "util/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <system_error>

namespace util {

std::string errno_text(std::string_view what, const std::filesystem::path& path) {
    return std::string(what) + " " + path.string() + ": " + std::strerror(errno);
}

bool sync_directory(const std::filesystem::path& dir) {
    const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return false;
    const bool ok = ::fsync(fd) == 0;
    const int saved = errno;
    ::close(fd);
    errno = saved;
    return ok;
}

bool remove_stale_temp(const std::filesystem::path& file) {
    std::filesystem::path tmp = file;
    tmp += ".tmp";
    return ::unlink(tmp.c_str()) == 0;
}

std::string write_file_atomic(const std::filesystem::path& file, std::span<const uint8_t> bytes,
                              const AtomicWriteStep& on_step) {
    std::filesystem::path dir = file.parent_path();
    if (dir.empty()) dir = ".";
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) return "cannot create " + dir.string() + ": " + ec.message();
    std::filesystem::path tmp = file;
    tmp += ".tmp";
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) return errno_text("cannot create", tmp);
    std::size_t done = 0;
    while (done < bytes.size()) {
        const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            const std::string err = errno_text("cannot write", tmp);
            ::close(fd);
            ::unlink(tmp.c_str());
            return err;
        }
        done += static_cast<std::size_t>(n);
    }
    if (::fsync(fd) != 0) {
        const std::string err = errno_text("cannot sync", tmp);
        ::close(fd);
        ::unlink(tmp.c_str());
        return err;
    }
    ::close(fd);
    if (on_step) on_step("temp-written");
    if (::rename(tmp.c_str(), file.c_str()) != 0) {
        const std::string err = errno_text("cannot rename onto", file);
        ::unlink(tmp.c_str());
        return err;
    }
    if (on_step) on_step("renamed");
    if (!sync_directory(dir)) return errno_text("cannot sync directory", dir);
    if (on_step) on_step("done");
    return {};
}

}  // namespace util
