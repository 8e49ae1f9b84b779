// The bounded read of a file given to a program (see util/input_file.hpp).
#include "util/input_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace util {

namespace {

const char* kind(mode_t m) {
    if (S_ISDIR(m)) return "a directory";
    if (S_ISFIFO(m)) return "a FIFO";
    if (S_ISCHR(m)) return "a character device";
    if (S_ISBLK(m)) return "a block device";
    if (S_ISSOCK(m)) return "a socket";
    return "not a regular file";
}

template <class Buffer>
Buffer read_bounded(const std::filesystem::path& path, std::size_t max_bytes, std::string_view what) {
    const std::string p = path.string();
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
    if (fd < 0)
        throw InputFileError(p + ": cannot open the " + std::string(what) + ": " + std::strerror(errno));
    struct Closer {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    struct stat st {};
    if (::fstat(fd, &st) != 0)
        throw InputFileError(p + ": cannot read the " + std::string(what) + ": " + std::strerror(errno));
    if (!S_ISREG(st.st_mode))
        throw InputFileError(p + ": not a regular file (" + kind(st.st_mode) + "); the " + std::string(what) +
                             " must be a file");
    auto too_large = [&] {
        // "not an ESI file", "not a topology file": the article as the kind's first letter sounds (an
        // initialism such as ESI or ENI is spoken from a vowel sound).
        const bool an =
            !what.empty() && std::string_view("AEFHILMNORSXaeiou").find(what[0]) != std::string_view::npos;
        return InputFileError(p + ": larger than " + std::to_string(max_bytes) + " bytes: not " +
                              (an ? "an " : "a ") + std::string(what));
    };
    if (st.st_size < 0 || static_cast<unsigned long long>(st.st_size) > max_bytes) throw too_large();
    // The regular file may still grow while it is read: read at most one byte more than allowed.
    Buffer out(static_cast<std::size_t>(st.st_size) + 1, 0);
    std::size_t got = 0;
    for (;;) {
        if (got == out.size()) {
            if (out.size() > max_bytes) throw too_large();
            out.resize(std::min(max_bytes + 1, out.size() * 2));
        }
        const ssize_t n = ::read(fd, out.data() + got, out.size() - got);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0)
            throw InputFileError(p + ": cannot read the " + std::string(what) + ": " + std::strerror(errno));
        if (n == 0) break;
        got += static_cast<std::size_t>(n);
    }
    if (got > max_bytes) throw too_large();
    out.resize(got);
    return out;
}

}  // namespace

std::string read_input_file(const std::filesystem::path& path, std::size_t max_bytes, std::string_view what) {
    return read_bounded<std::string>(path, max_bytes, what);
}

std::vector<uint8_t> read_input_bytes(const std::filesystem::path& path, std::size_t max_bytes,
                                      std::string_view what) {
    return read_bounded<std::vector<uint8_t>>(path, max_bytes, what);
}

}  // namespace util
