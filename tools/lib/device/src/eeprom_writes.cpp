// Master-written SII words kept across restarts (see device/eeprom_writes.hpp).
#include "device/eeprom_writes.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "esc/wire/sii.hpp"
#include "od/store.hpp"
#include "util/atomic_file.hpp"
#include "util/crc.hpp"
#include "util/le.hpp"
#include "util/strfmt.hpp"

namespace device {

namespace {

constexpr char kMagic[8] = {'S', 'E', 'C', 'A', 'T', 'S', 'I', 'I'};
constexpr std::size_t kMaxWords = 65536;
constexpr std::size_t kMaxFileBytes = 16 + 4 * kMaxWords;  // every word of a 64 Ki-word EEPROM once

using util::get32;
void put32(std::vector<uint8_t>& b, uint32_t v) {
    util::append32(b, v);
}
std::string sys_error(const std::string& what, const std::filesystem::path& p) {
    return what + " " + p.string() + ": " + std::strerror(errno);
}

}  // namespace

EepromWrites::EepromWrites(std::filesystem::path state_dir)
    : dir_(std::move(state_dir)), file_(dir_ / kFileName) {}

std::string EepromWrites::load() {
    words_.clear();
    // The size is checked against what a valid file can hold before anything is read or reserved, and
    // only a regular file is read (O_NONBLOCK: a FIFO in its place must not hang the start).
    const int fd = ::open(file_.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) return errno == ENOENT ? std::string{} : sys_error("cannot open", file_);
    struct stat st {};
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        ::close(fd);
        return "not a regular file";
    }
    if (static_cast<uint64_t>(st.st_size) > kMaxFileBytes) {
        ::close(fd);
        return "file of " + std::to_string(st.st_size) + " bytes, larger than any SII writes file";
    }
    std::vector<uint8_t> b(static_cast<std::size_t>(st.st_size));
    std::size_t got = 0;
    while (got < b.size()) {
        const ssize_t n = ::read(fd, b.data() + got, b.size() - got);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;
        got += static_cast<std::size_t>(n);
    }
    ::close(fd);
    b.resize(got);
    if (b.size() < 16 || std::memcmp(b.data(), kMagic, 8) != 0) return "not an SII writes file";
    const uint32_t n = get32(b.data() + 8);
    if (n > kMaxWords || b.size() != 16 + 4 * static_cast<std::size_t>(n)) return "length does not match";
    if (util::crc32(std::span<const uint8_t>(b.data(), b.size() - 4)) != get32(b.data() + b.size() - 4))
        return "checksum mismatch";
    for (uint32_t i = 0; i < n; ++i) {
        const uint8_t* p = b.data() + 12 + 4 * i;
        words_[util::get16(p)] = util::get16(p + 2);
    }
    return {};
}

bool EepromWrites::remove_stale_temp() const {
    return util::remove_stale_temp(file_);
}

std::string EepromWrites::save() {
    std::vector<uint8_t> b(kMagic, kMagic + 8);
    put32(b, static_cast<uint32_t>(words_.size()));
    for (const auto& [address, value] : words_) {
        util::append16(b, address);
        util::append16(b, value);
    }
    put32(b, util::crc32(b));
    return util::write_file_atomic(file_, b);
}

void EepromWrites::apply(std::vector<uint8_t>& image) const {
    for (const auto& [address, value] : words_) {
        const std::size_t at = 2 * static_cast<std::size_t>(address);
        if (at + 1 >= image.size()) continue;
        util::put16(image.data() + at, value);
    }
}

std::vector<std::string> sii_drift(std::span<const uint8_t> image, uint32_t vendor_id, uint32_t product_code,
                                   uint32_t revision, uint32_t serial_number) {
    std::vector<std::string> out;
    if (image.size() < 32) {
        out.push_back("the image has " + std::to_string(image.size()) +
                      " bytes, too short for the SII header and identity (32 bytes)");
        return out;
    }
    using util::hex;
    const uint8_t crc = esc::sii::crc8(image.data(), 14);
    if (crc != image[14])
        out.push_back("SII checksum (word 7) is " + hex(image[14], 2) + ", words 0-6 give " + hex(crc, 2) +
                      " (a master checks it and may refuse the slave)");
    struct Field {
        const char* name;
        std::size_t at;
        uint32_t model;
    };
    const Field fields[] = {{"vendor id", 0x10, vendor_id},
                            {"product code", 0x14, product_code},
                            {"revision", 0x18, revision},
                            {"serial number", 0x1C, serial_number}};
    int sub = 1;
    for (const Field& f : fields) {
        const uint32_t v = get32(image.data() + f.at);
        if (v != f.model)
            out.push_back("SII " + std::string(f.name) + " " + hex(v, 8) + " differs from 0x1018:0" +
                          std::to_string(sub) + " " + hex(f.model, 8));
        ++sub;
    }
    return out;
}

}  // namespace device
