// `ecatctl sii read|write|decode`: the SII EEPROM (decoded with the od-free SII reader).
#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "common.hpp"
#include "esi/sii_reader.hpp"
#include "format.hpp"
#include "master/coe.hpp"
#include "master/foe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"
#include "util/le.hpp"
#include "util/strfmt.hpp"

namespace ecatctl {

namespace {

using master::Address;
using master::Error;

struct SiiArgs {
    std::string slave = "0";
    bool station = false;
    std::string output;
    std::string input;
    bool all = false;
    bool force = false;
};

int sii_read(master::Master& m, const SiiArgs& s) {
    auto a = named_slave(s.slave, s.station);
    if (!a) return kExitUsage;
    auto img = m.sii_read_image(*a, s.all);
    if (!img) return fail(img.error(), "reading the SII of " + slave_label(*a));
    if (s.output.empty()) {
        std::fputs(hex_dump(0, *img).c_str(), stdout);
        return kExitOk;
    }
    if (s.output == "-") {
        std::fwrite(img->data(), 1, img->size(), stdout);
        return kExitOk;
    }
    std::ofstream f(s.output, std::ios::binary | std::ios::trunc);
    f.write(reinterpret_cast<const char*>(img->data()), static_cast<std::streamsize>(img->size()));
    if (!f) {
        std::cerr << "ecatctl: cannot write " << s.output << ": " << std::strerror(errno) << "\n";
        return kExitFailure;
    }
    std::cerr << "ecatctl: " << img->size() << " bytes written to " << s.output << "\n";
    return kExitOk;
}

int sii_write(master::Master& m, const SiiArgs& s) {
    auto a = named_slave(s.slave, s.station);
    if (!a) return kExitUsage;
    auto img = read_file(s.input, kMaxSiiBytes, "SII image");
    if (!img) return kExitUsage;
    if (img->size() < 16 || img->size() % 2 != 0 || img->size() > 65536)
        return usage_error(s.input + ": an SII image is an even number of bytes, 16 to 65536");
    const uint16_t w7 = util::get16(img->data() + 2 * esc::sii::word::Checksum);
    const uint8_t crc = esc::sii::crc8(img->data(), esc::sii::kCrcBytes);
    if (w7 != esc::sii::kChecksumDisabled && (w7 & 0xFF) != crc && !s.force) {
        return usage_error(
            util::strprintf("%s: checksum word 7 is 0x%04x, CRC of words 0-6 is 0x%02x (use --force)",
                            s.input.c_str(), w7, crc));
    }
    const std::size_t words = img->size() / 2;
    for (std::size_t w = 0; w < words; ++w) {
        const uint16_t v = util::get16(img->data() + 2 * w);
        if (Error e = m.sii_write_word(*a, static_cast<uint32_t>(w), v); e != Error::Ok)
            return fail(e, "writing SII word " + std::to_string(w) + " of " + slave_label(*a));
    }
    std::cerr << "ecatctl: " << words << " words written\n";
    return kExitOk;
}

}  // namespace

void add_sii_command(CLI::App& app, MasterRunner run, int& rc) {
    auto s = std::make_shared<SiiArgs>();
    auto* sii = app.add_subcommand("sii", "SII EEPROM")->require_subcommand(1);
    auto* sii_rd = sii->add_subcommand("read", "Read the image (header and categories up to the end marker)");
    sii_rd->add_option("-p,--position", s->slave, "Slave position (or station address with --station)")
        ->capture_default_str();
    sii_rd->add_flag("-s,--station", s->station, "--position is a station address");
    sii_rd->add_option("-o,--output", s->output,
                       "Write the raw image to this file ('-': stdout); default: hex dump");
    sii_rd->add_flag("-a,--all", s->all,
                     "Read the whole EEPROM size from word 0x3E, not only up to the end marker");
    sii_rd->callback([s, run, &rc] { rc = run([&](master::Master& m) { return sii_read(m, *s); }); });
    auto* sii_wr = sii->add_subcommand("write", "Write an image file word by word");
    sii_wr->add_option("file", s->input, "Binary image")->required()->check(CLI::ExistingFile);
    sii_wr->add_option("-p,--position", s->slave, "Slave position (or station address with --station)")
        ->capture_default_str();
    sii_wr->add_flag("-s,--station", s->station, "--position is a station address");
    sii_wr->add_flag("-f,--force", s->force, "Write even if the checksum in word 7 is wrong");
    sii_wr->callback([s, run, &rc] { rc = run([&](master::Master& m) { return sii_write(m, *s); }); });
    auto* sii_dec =
        sii->add_subcommand("decode", "Print the content of an image file, or of the slave's SII");
    sii_dec->add_option("file", s->input, "Binary image (default: read it from the slave)");
    sii_dec->add_option("-p,--position", s->slave, "Slave position (or station address with --station)")
        ->capture_default_str();
    sii_dec->add_flag("-s,--station", s->station, "--position is a station address");
    sii_dec->callback([s, run, &rc] {
        if (!s->input.empty()) {
            auto img = read_file(s->input, kMaxSiiBytes, "SII image");
            if (!img) {
                rc = kExitUsage;
                return;
            }
            std::fputs(esi::decode_sii(*img).c_str(), stdout);
            rc = sii_problems(s->input, *img) ? kExitUsage : kExitOk;  // an empty or corrupt file
            return;
        }
        rc = run([&](master::Master& m) {
            auto a = named_slave(s->slave, s->station);
            if (!a) return kExitUsage;
            auto img = m.sii_read_image(*a);
            if (!img) return fail(img.error(), "reading the SII of " + slave_label(*a));
            std::fputs(esi::decode_sii(*img).c_str(), stdout);
            return sii_problems("the SII of " + slave_label(*a), *img) ? kExitProtocol : kExitOk;
        });
    });
}

}  // namespace ecatctl
