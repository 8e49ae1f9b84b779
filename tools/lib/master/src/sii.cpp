// SII EEPROM access through the ESC's EEPROM interface (0x0500-0x050F, ESC datasheet section II).
// Works with both read sizes (4 and 8 bytes, 0x0502 bit 6), waits while busy or while the command bits
// are still set (as IgH), clears stale error bits before a command (as SOEM) and repeats a command the
// interface reports as not acknowledged (bit 13).
#include <algorithm>
#include <thread>

#include "master/master.hpp"

#include "util/le.hpp"

namespace master {

using Clock = std::chrono::steady_clock;

namespace {
using util::put32;
constexpr std::size_t kMaxImageWords = 32768;  // 64 KiB: bound of the category walk (decisions/master.md)
constexpr unsigned kNackRetries = 5;

}  // namespace

Error Master::sii_take(Address a) {
    uint8_t cfg[2];
    if (Error e = read(a, reg::SiiConfig, cfg); e != Error::Ok) return e;
    // 0x0500 bit 0: offered to the PDI; 0x0501 bit 0: the PDI holds it. Force it back (bit 1), then
    // keep it on the ECAT side.
    if ((cfg[0] & 0x01) || (cfg[1] & 0x01)) {
        const uint8_t force = 0x02, release = 0x00;
        if (Error e = write(a, reg::SiiConfig, std::span<const uint8_t>(&force, 1)); e != Error::Ok) return e;
        if (Error e = write(a, reg::SiiConfig, std::span<const uint8_t>(&release, 1)); e != Error::Ok)
            return e;
    }
    return Error::Ok;
}

Error Master::sii_wait(Address a, uint16_t& status, std::span<uint8_t> data_out) {
    const auto deadline = Clock::now() + options_.sii_timeout;
    for (;;) {
        uint8_t b[14];  // 0x0502 control/status, 0x0504 address, 0x0508 data (up to 8 bytes)
        if (Error e = read(a, reg::SiiControl, b); e != Error::Ok) return e;
        status = util::get16(b);
        if (!(status & sii::Busy) && !(status & sii::CmdMask)) {
            std::copy_n(b + 6, std::min<std::size_t>(data_out.size(), 8), data_out.begin());
            return Error::Ok;
        }
        if (Clock::now() >= deadline) return Error::SiiBusy;
        std::this_thread::sleep_for(std::chrono::microseconds(50));
    }
}

Error Master::sii_command(Address a, uint16_t command, uint32_t word, std::span<uint8_t> data_out,
                          const uint16_t* write_value) {
    for (unsigned attempt = 0; attempt < kNackRetries; ++attempt) {
        uint16_t status = 0;
        if (Error e = sii_wait(a, status); e != Error::Ok) return e;
        if (status & (sii::ErrAck | sii::ErrWriteEnable)) {
            // Command 000 clears the error bits.
            if (Error e = write_reg<uint16_t>(a, reg::SiiControl, 0); e != Error::Ok) return e;
            if (Error e = sii_wait(a, status); e != Error::Ok) return e;
        }
        uint8_t ctl[6];
        const uint16_t c =
            static_cast<uint16_t>(command | (command == sii::CmdWrite ? sii::CtlWriteEnable : 0));
        ctl[0] = static_cast<uint8_t>(c);
        ctl[1] = static_cast<uint8_t>(c >> 8);
        put32(ctl + 2, word);
        uint8_t data[2] = {};
        Datagram d[2];
        std::size_t n = 0;
        if (write_value) {
            // The data word goes in first (datagram order is execution order), then the command.
            data[0] = static_cast<uint8_t>(*write_value);
            data[1] = static_cast<uint8_t>(*write_value >> 8);
            d[n++] = addressed(a, true, reg::SiiData, data);
        }
        d[n++] = addressed(a, true, reg::SiiControl, ctl);
        if (Error e = exchange(std::span<Datagram>(d, n)); e != Error::Ok) return e;
        for (std::size_t i = 0; i < n; ++i)
            if (d[i].wkc != 1) return Error::WorkingCounter;
        if (Error e = sii_wait(a, status, data_out); e != Error::Ok) return e;
        if (status & sii::ErrAck) continue;  // not acknowledged: issue the command again
        if (command == sii::CmdWrite && (status & sii::ErrWriteEnable)) return Error::SiiWriteDisabled;
        if (command == sii::CmdRead && data_out.size() >= 8 && !(status & sii::CtlReadSize8)) {
            std::fill(data_out.begin() + 4, data_out.end(), 0);  // only 4 bytes are valid
        }
        // Read size reported to the caller through the status bit in data_out's owner (see sii_read).
        last_sii_status_ = status;
        return Error::Ok;
    }
    return Error::SiiNack;
}

Error Master::sii_read(Address a, uint32_t word, std::span<uint8_t> out) {
    if (out.empty()) return Error::InvalidArgument;
    if (Error e = sii_take(a); e != Error::Ok) return e;
    std::size_t done = 0;
    while (done < out.size()) {
        uint8_t chunk[8] = {};
        if (Error e = sii_command(a, sii::CmdRead, word, chunk, nullptr); e != Error::Ok) return e;
        const std::size_t got = (last_sii_status_ & sii::CtlReadSize8) ? 8 : 4;
        const std::size_t take = std::min(got, out.size() - done);
        std::copy_n(chunk, take, out.begin() + static_cast<std::ptrdiff_t>(done));
        done += take;
        word += static_cast<uint32_t>(got / 2);
    }
    return Error::Ok;
}

Result<uint16_t> Master::sii_read_word(Address a, uint32_t word) {
    uint8_t b[2];
    if (Error e = sii_read(a, word, b); e != Error::Ok) return e;
    return util::get16(b);
}

Result<uint32_t> Master::sii_read_u32(Address a, uint32_t word) {
    uint8_t b[4];
    if (Error e = sii_read(a, word, b); e != Error::Ok) return e;
    return util::get32(b);
}

Result<bool> Master::sii_has_mailbox(Address a) {
    uint8_t w[8];  // words 0x18-0x1B: SM0 and SM1 of the standard mailbox, offset and size
    if (Error e = sii_read(a, sii::StdMailboxOut, w); e != Error::Ok) return e;
    return std::any_of(std::begin(w), std::end(w), [](uint8_t b) { return b != 0; });
}

Result<std::vector<uint8_t>> Master::sii_read_image(Address a, bool whole_eeprom) {
    std::vector<uint8_t> image;
    if (Error e = sii_take(a); e != Error::Ok) return e;
    // Reads sequentially (4 or 8 bytes per command) until at least `words` words are there.
    auto ensure = [&](std::size_t words) -> Error {
        while (image.size() < words * 2) {
            uint8_t chunk[8] = {};
            const auto at = static_cast<uint32_t>(image.size() / 2);
            if (Error e = sii_command(a, sii::CmdRead, at, chunk, nullptr); e != Error::Ok) return e;
            const std::size_t got = (last_sii_status_ & sii::CtlReadSize8) ? 8 : 4;
            image.insert(image.end(), chunk, chunk + got);
        }
        return Error::Ok;
    };
    auto word_at = [&](std::size_t w) { return util::get16(image.data() + 2 * w); };

    if (Error e = ensure(sii::FirstCategory); e != Error::Ok) return e;
    if (whole_eeprom) {
        const uint16_t kbit = word_at(sii::EepromSize);
        const std::size_t words =
            std::min<std::size_t>((static_cast<std::size_t>(kbit) + 1) * 64, kMaxImageWords);
        if (Error e = ensure(words); e != Error::Ok) return e;
        image.resize(words * 2);
        return image;
    }
    std::size_t w = sii::FirstCategory;
    for (;;) {
        if (w + 1 > kMaxImageWords) return Error::SiiFormat;
        if (Error e = ensure(w + 1); e != Error::Ok) return e;
        if (word_at(w) == sii::CategoryEnd) {
            image.resize((w + 1) * 2);
            return image;
        }
        if (Error e = ensure(w + 2); e != Error::Ok) return e;
        w += 2 + static_cast<std::size_t>(word_at(w + 1));
    }
}

Error Master::sii_write_word(Address a, uint32_t word, uint16_t value) {
    if (Error e = sii_take(a); e != Error::Ok) return e;
    return sii_command(a, sii::CmdWrite, word, {}, &value);
}

}  // namespace master
