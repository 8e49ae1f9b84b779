// ecatctl firmware-update FILE: the firmware update over FoE of the EPOS4 Application Notes §4.2-4.9 as a
// master runs it, with every step checked and every failure named:
//   1. identity and revision from the SII and from 0x1018 / 0x100A / 0x1008 (CoE, in PREOP); the drive
//      must not be switched on (step 1 of the procedure: device control "Disabled");
//   2. the image header must be for this vendor and product (checked here, before anything is sent);
//   3. ESC -> Bootstrap (INIT first, the bootstrap mailbox from SII words 0x14-0x17);
//   4. FoE write of the image to the device's name (the application notes: file `EPOS4` for EPOS4, i.e.
//   0x1008), password;
//   5. ESC -> Init: the device resets (B->I "reset device after a successful firmware download");
//   6. wait for the restart (AL status answers INIT again, the SII header reads back);
//   7. the revision in the SII, 0x1018:03 and 0x100A must be the image's version.
// A failure after Bootstrap was entered still takes the device back to Init (it restarts with the firmware
// it had) and reports the revision it runs afterwards.
#include "cmd_firmware.hpp"

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdarg>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

#include "commands.hpp"
#include "common.hpp"
#include "foe/image.hpp"
#include "format.hpp"
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "util/le.hpp"
#include "util/strfmt.hpp"

namespace ecatctl {

using master::Address;
using master::AlState;
using master::Error;
using Clock = std::chrono::steady_clock;

// ---- progress bar --------------------------------------------------------------------------------

ProgressBar::ProgressBar(std::string label, bool force)
    : label_(std::move(label)), tty_(::isatty(STDERR_FILENO) == 1), start_(Clock::now()) {
    enabled_ = force || tty_;
}

std::function<void(const master::FoeProgress&)> ProgressBar::callback() {
    if (!enabled_) return {};
    return [this](const master::FoeProgress& p) { update(p); };
}

namespace {
std::string rate_text(double bytes_per_s) {
    char b[32];
    if (bytes_per_s >= 1e6)
        std::snprintf(b, sizeof b, "%.2f MB/s", bytes_per_s / 1e6);
    else
        std::snprintf(b, sizeof b, "%.1f kB/s", bytes_per_s / 1e3);
    return b;
}
}  // namespace

void ProgressBar::draw(const master::FoeProgress& p, bool final) {
    const double s = std::chrono::duration<double>(Clock::now() - start_).count();
    const double rate = s > 0 ? static_cast<double>(p.done) / s : 0.0;
    const int pct =
        p.total ? static_cast<int>(100.0 * static_cast<double>(p.done) / static_cast<double>(p.total)) : 0;
    if (tty_) {
        constexpr int kWidth = 30;
        const int fill = p.total ? pct * kWidth / 100 : 0;
        std::string bar(static_cast<std::size_t>(fill), '#');
        bar.resize(kWidth, '.');
        std::fprintf(stderr, "\r%s [%s] %zu/%zu bytes %3d%% %s%s\033[K", label_.c_str(), bar.c_str(), p.done,
                     p.total, pct, rate_text(rate).c_str(), p.busy ? " storing..." : "");
        if (final) std::fputc('\n', stderr);
    } else {
        std::fprintf(stderr, "ecatctl: %s %zu/%zu bytes %d%% %s\n", label_.c_str(), p.done, p.total, pct,
                     rate_text(rate).c_str());
    }
    std::fflush(stderr);
    drawn_ = true;
}

void ProgressBar::update(const master::FoeProgress& p) {
    if (!enabled_) return;
    last_ = p;
    const auto now = Clock::now();
    if (p.busy) {
        if (!storing_said_) {
            storing_said_ = true;
            if (tty_) {
                draw(p, false);
            } else {
                std::fprintf(stderr, "ecatctl: %s all %zu bytes sent, the slave is storing the image\n",
                             label_.c_str(), p.done);
                std::fflush(stderr);
            }
            last_draw_ = now;
        }
        return;
    }
    if (tty_) {
        if (!drawn_ || now - last_draw_ >= std::chrono::milliseconds(100) || p.done == p.total) {
            draw(p, false);
            last_draw_ = now;
        }
        return;
    }
    const int decile = p.total ? static_cast<int>(10 * p.done / p.total) : 0;
    if (decile != last_decile_) {
        last_decile_ = decile;
        draw(p, false);
    }
}

void ProgressBar::finish() {
    if (!enabled_ || !drawn_) return;
    if (tty_) draw(last_, true);
}

// ---- firmware-update -----------------------------------------------------------------------------

namespace {

struct Args {
    std::string file;
    std::string slave = "0";
    bool station = false;
    std::string password = "0";
    std::string name;
    bool force = false;
    bool no_boot = false;
    bool progress = false;
    unsigned restart_timeout_ms = 20000;
};

struct Identity {
    uint32_t vendor = 0, product = 0, revision = 0, serial = 0;
};

// The steps print as they go, with the time since the start: "[  1.234 s] ...".
class Steps {
  public:
    void say(const char* fmt, ...) __attribute__((format(printf, 2, 3))) {
        std::fprintf(stderr, "ecatctl: [%7.3f s] ", seconds());
        va_list ap;
        va_start(ap, fmt);
        std::vfprintf(stderr, fmt, ap);
        va_end(ap);
        std::fputc('\n', stderr);
    }
    double seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

  private:
    Clock::time_point start_ = Clock::now();
};

Error read_sii_identity(master::Master& m, Address a, Identity& id) {
    uint8_t b[16];
    if (Error e = m.sii_read(a, master::sii::VendorId, b); e != Error::Ok) return e;
    id = Identity{util::get32(b), util::get32(b + 4), util::get32(b + 8), util::get32(b + 12)};
    return Error::Ok;
}

// What CoE says about the running firmware (PREOP).
struct CoeIdentity {
    Identity id;
    std::string name;     // 0x1008
    std::string version;  // 0x100A
    uint16_t statusword = 0;
    bool have_statusword = false;
};

int sdo_failed(const master::SdoClient& sdo, Error e, const std::string& what) {
    return report_sdo_failure(sdo, e, what, fail);
}

int refused(const char* target, const master::AlStatus& st) {
    std::fprintf(stderr, "ecatctl: device refused %s: stays in %s, AL status code 0x%04x (%s)\n", target,
                 std::string(master::al_state_name(st.state)).c_str(), st.code,
                 std::string(master::al_status_code_name(st.code)).c_str());
    return kExitProtocol;
}

// INIT -> PREOP with the standard mailbox from the SII (a slave in PREOP or above keeps its SMs), then
// 0x1018:01..04, 0x1008, 0x100A and the statusword.
int read_coe_identity(master::Master& m, Address a, CoeIdentity& out) {
    master::Mailbox mbx(m, a);
    auto st = m.al_status(a);
    if (!st) return report_error(st.error(), "reading the AL status");
    if (st->state == static_cast<uint8_t>(AlState::Init) ||
        st->state == static_cast<uint8_t>(AlState::Boot)) {
        if (st->state == static_cast<uint8_t>(AlState::Boot)) {
            if (Error e = m.request_state(a, AlState::Init); e != Error::Ok)
                return report_error(e, "going to INIT");
        }
        if (Error e = mbx.configure_from_sii(); e != Error::Ok)
            return report_error(e, "setting up the mailbox from the SII");
        master::AlStatus final;
        const Error e = m.request_state(a, AlState::PreOp, &final);
        if (e == Error::AlRefused) return refused("PREOP", final);
        if (e != Error::Ok) return report_error(e, "going to PREOP");
    } else if (Error e = mbx.adopt_current(); e != Error::Ok) {
        return report_error(e, "opening the mailbox");
    }
    master::SdoClient sdo(mbx);
    uint8_t b[128];
    uint32_t* fields[] = {&out.id.vendor, &out.id.product, &out.id.revision, &out.id.serial};
    for (uint8_t sub = 1; sub <= 4; ++sub) {
        auto n = sdo.upload(0x1018, sub, std::span<uint8_t>(b, 4));
        if (!n) return sdo_failed(sdo, n.error(), "reading 0x1018:0" + std::to_string(sub));
        *fields[sub - 1] = util::get32(b);
    }
    auto text = [&](uint16_t index, std::string& s) -> int {
        auto n = sdo.upload(index, 0, b);
        if (!n) {
            return sdo_failed(sdo, n.error(), util::strprintf("reading 0x%04X", index));
        }
        s.assign(reinterpret_cast<const char*>(b), *n);
        while (!s.empty() && s.back() == '\0')
            s.pop_back();
        return kExitOk;
    };
    if (int rc = text(0x1008, out.name); rc != kExitOk) return rc;
    if (int rc = text(0x100A, out.version); rc != kExitOk) return rc;
    if (auto n = sdo.upload(0x6041, 0, std::span<uint8_t>(b, 2))) {
        out.statusword = util::get16(b);
        out.have_statusword = true;
    }
    return kExitOk;
}

// B -> I: the device resets. Waits until the AL status answers INIT without an error again and the SII
// header reads back (frames may go unanswered while the device rebuilds).
int restart(master::Master& m, Address a, const Args& args, Steps& steps, Identity& sii) {
    const auto deadline = Clock::now() + std::chrono::milliseconds(args.restart_timeout_ms);
    master::AlStatus final;
    Error e = m.request_state(a, AlState::Init, &final);
    if (e == Error::AlRefused) return refused("INIT", final);
    if (e != Error::Ok)
        steps.say("no answer while the device restarts (%s); waiting",
                  std::string(master::to_string(e)).c_str());
    for (;;) {
        auto st = m.al_status(a);
        if (st && st->state == static_cast<uint8_t>(AlState::Init) && !st->error) break;
        if (st && st->error) {
            (void)m.write_reg<uint16_t>(a, master::reg::AlControl,
                                        static_cast<uint16_t>(st->state | master::kAlErrorAck));
        } else if (st && st->state != static_cast<uint8_t>(AlState::Init)) {
            (void)m.write_reg<uint16_t>(a, master::reg::AlControl, static_cast<uint8_t>(AlState::Init));
        }
        if (Clock::now() >= deadline) {
            if (!st) return report_error(st.error(), "waiting for the device to restart");
            std::fprintf(stderr,
                         "ecatctl: the device did not come back in INIT within %u ms (AL status %s%s)\n",
                         args.restart_timeout_ms, std::string(master::al_state_name(st->state)).c_str(),
                         st->error ? " +ERR" : "");
            return kExitProtocol;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    for (;;) {
        e = read_sii_identity(m, a, sii);
        if (e == Error::Ok) break;
        if (Clock::now() >= deadline) return report_error(e, "reading the SII after the restart");
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return kExitOk;
}

// After a failure in Bootstrap: back to INIT (the device restarts with the firmware it kept) and say
// which revision runs now.
void recover(master::Master& m, Address a, const Args& args, Steps& steps) {
    Identity now;
    if (restart(m, a, args, steps, now) == kExitOk)
        steps.say("device back in INIT, running revision 0x%08x", now.revision);
}

struct Image {
    std::vector<uint8_t> bytes;
    foe::ImageHeader head{};
};

// The image: a well-formed header and the right CRC, checked before the link is opened and the device
// touched.
int load_image(const Args& args, Image& out) {
    auto image = read_file(args.file, kMaxFileBytes, "firmware image");
    if (!image) return kExitUsage;
    if (image->size() < foe::kImageHeaderSize) {
        std::fprintf(stderr, "ecatctl: %s: not a firmware image (%zu bytes, shorter than its header)\n",
                     args.file.c_str(), image->size());
        if (!args.force) return kExitUsage;
    }
    foe::ImageHeader head{};
    if (image->size() >= foe::kImageHeaderSize)
        head = foe::decode_header(
            std::span<const uint8_t, foe::kImageHeaderSize>(image->data(), foe::kImageHeaderSize));
    const foe::ImageIdentity own{head.vendor_id, head.product_code};
    const foe::VerifyResult v = foe::verify_image(*image, own);
    if (!v.ok()) {
        std::fprintf(stderr, "ecatctl: %s: not a valid firmware image: %s%s\n", args.file.c_str(),
                     foe::describe(v, own).c_str(), args.force ? " (--force: sending it anyway)" : "");
        if (!args.force) return kExitUsage;
    }
    out.bytes = std::move(*image);
    out.head = head;
    return kExitOk;
}

int firmware_update(master::Master& m, const Args& args, const Image& img) {
    const std::vector<uint8_t>* image = &img.bytes;
    const foe::ImageHeader& head = img.head;
    Steps steps;
    auto slave_no = parse_number(args.slave, 0xFFFF);
    if (!slave_no) {
        std::fprintf(stderr, "ecatctl: bad slave '%s'\n", args.slave.c_str());
        return kExitUsage;
    }
    const Address a = args.station ? Address::station(static_cast<uint16_t>(*slave_no))
                                   : Address::position(static_cast<uint16_t>(*slave_no));
    auto password = parse_number(args.password, 0xFFFFFFFF);
    if (!password) {
        std::fprintf(stderr, "ecatctl: bad password '%s'\n", args.password.c_str());
        return kExitUsage;
    }

    steps.say("image %s: %zu bytes, vendor 0x%08x, product 0x%08x, version 0x%08x (%s)", args.file.c_str(),
              image->size(), head.vendor_id, head.product_code, head.version,
              foe::software_version_text(head.version).c_str());

    // 1. The device as it runs now. A device left in BOOT by an interrupted update is reset first.
    auto st = m.al_status(a);
    if (!st) return report_error(st.error(), "reading the AL status");
    if (st->state == static_cast<uint8_t>(AlState::Boot)) {
        steps.say("device is in BOOT (an earlier update did not finish): resetting it to INIT");
        Identity ignored;
        if (int rc = restart(m, a, args, steps, ignored); rc != kExitOk) return rc;
    }
    Identity sii;
    if (Error e = read_sii_identity(m, a, sii); e != Error::Ok)
        return report_error(e, "reading the identity from the SII");
    CoeIdentity coe;
    if (int rc = read_coe_identity(m, a, coe); rc != kExitOk) return rc;
    steps.say("device '%s': vendor 0x%08x, product 0x%08x, revision 0x%08x (0x100A '%s'), serial 0x%08x",
              coe.name.c_str(), coe.id.vendor, coe.id.product, coe.id.revision, coe.version.c_str(),
              coe.id.serial);
    if (sii.vendor != coe.id.vendor || sii.product != coe.id.product || sii.revision != coe.id.revision)
        steps.say("warning: the SII says vendor 0x%08x, product 0x%08x, revision 0x%08x", sii.vendor,
                  sii.product, sii.revision);
    if (coe.have_statusword && (coe.statusword & 0x0002) != 0 && !args.force) {
        std::fprintf(stderr,
                     "ecatctl: the drive is switched on (statusword 0x%04x): disable it before an update "
                     "(step 1 of the update procedure), or use --force\n",
                     coe.statusword);
        return kExitFailure;
    }

    // 2. The image must be for this device.
    if (head.vendor_id != coe.id.vendor || head.product_code != coe.id.product) {
        std::fprintf(stderr,
                     "ecatctl: %s is for vendor 0x%08x product 0x%08x, this device is vendor 0x%08x product "
                     "0x%08x%s\n",
                     args.file.c_str(), head.vendor_id, head.product_code, coe.id.vendor, coe.id.product,
                     args.force ? " (--force: sending it anyway)" : "");
        if (!args.force) return kExitUsage;
    }
    if (head.version == coe.id.revision) steps.say("the device runs this version already; writing it again");
    const std::string name =
        args.name.empty() ? (coe.name.empty() ? std::string("MAXPOS") : coe.name) : args.name;

    // 3. Bootstrap.
    master::Mailbox mbx(m, a);
    if (args.no_boot) {
        if (Error e = mbx.adopt_current(); e != Error::Ok) return report_error(e, "opening the mailbox");
        steps.say("--no-boot: writing in the current state");
    } else {
        master::AlStatus final;
        if (Error e = m.request_state(a, AlState::Init, &final); e != Error::Ok)
            return e == Error::AlRefused ? refused("INIT", final) : report_error(e, "going to INIT");
        if (Error e = mbx.configure_from_sii(true); e != Error::Ok)
            return report_error(e, "setting up the bootstrap mailbox (SII words 0x14-0x17)");
        const Error e = m.request_state(a, AlState::Boot, &final);
        if (e == Error::AlRefused) return refused("BOOT", final);
        if (e != Error::Ok) return report_error(e, "going to BOOT");
        steps.say("BOOT (bootstrap mailbox %u/%u bytes)", mbx.config().out_size, mbx.config().in_size);
    }

    // 4. FoE write.
    master::FoeClient foe(mbx);
    ProgressBar bar("writing '" + name + "'", args.progress);
    foe.set_progress(bar.callback());
    const auto t0 = Clock::now();
    const Error we = foe.write(name, *image, static_cast<uint32_t>(*password));
    bar.finish();
    if (we != Error::Ok) {
        if (we == Error::FoeError)
            std::fprintf(stderr, "ecatctl: writing '%s': FoE error 0x%04x%s%s\n", name.c_str(),
                         foe.last_error(), foe.last_error_text().empty() ? "" : ": ",
                         foe.last_error_text().c_str());
        else if (we == Error::MailboxError)
            std::fprintf(stderr, "ecatctl: writing '%s': mailbox error (the device serves no FoE here)\n",
                         name.c_str());
        else
            (void)report_error(we, "writing '" + name + "'");
        if (!args.no_boot) recover(m, a, args, steps);
        return exit_code(we);
    }
    const double secs = std::chrono::duration<double>(Clock::now() - t0).count();
    steps.say("%zu bytes written to '%s' in %.3f s (%.2f MB/s, %llu BUSY answers)", image->size(),
              name.c_str(), secs, secs > 0 ? static_cast<double>(image->size()) / secs / 1e6 : 0.0,
              static_cast<unsigned long long>(foe.busy_answers()));
    if (args.no_boot) return kExitOk;

    // 5./6. Init: the device resets into the new firmware.
    Identity after_sii;
    if (int rc = restart(m, a, args, steps, after_sii); rc != kExitOk) return rc;
    steps.say("device restarted: INIT, SII revision 0x%08x", after_sii.revision);

    // 7. The revision everywhere.
    CoeIdentity after;
    if (int rc = read_coe_identity(m, a, after); rc != kExitOk) return rc;
    (void)m.request_state(a, AlState::Init);  // leave it in the state a reset gives
    const std::string want_text = foe::software_version_text(head.version);
    bool ok = true;
    if (after_sii.revision != head.version) {
        std::fprintf(stderr, "ecatctl: the SII reports revision 0x%08x, the image is 0x%08x\n",
                     after_sii.revision, head.version);
        ok = false;
    }
    if (after.id.revision != head.version) {
        std::fprintf(stderr, "ecatctl: 0x1018:03 reports revision 0x%08x, the image is 0x%08x\n",
                     after.id.revision, head.version);
        ok = false;
    }
    if (after.id.vendor != head.vendor_id || after.id.product != head.product_code) {
        // Step 6 of the procedure checks 0x1018:02 (hardware version and application number) as well.
        std::fprintf(stderr,
                     "ecatctl: 0x1018 reports vendor 0x%08x product 0x%08x, the image is for 0x%08x 0x%08x\n",
                     after.id.vendor, after.id.product, head.vendor_id, head.product_code);
        ok = false;
    }
    if (after.version != want_text) {
        std::fprintf(stderr, "ecatctl: 0x100A reports '%s', the image is '%s'\n", after.version.c_str(),
                     want_text.c_str());
        ok = false;
    }
    if (!ok) {
        std::fprintf(stderr, "ecatctl: the update was not taken: the device still runs revision 0x%08x\n",
                     after.id.revision);
        return kExitProtocol;
    }
    steps.say("firmware updated: revision 0x%08x -> 0x%08x (0x100A '%s' -> '%s')", coe.id.revision,
              after.id.revision, coe.version.c_str(), after.version.c_str());
    std::printf("0x%08x\n", after.id.revision);
    return kExitOk;
}

}  // namespace

void add_firmware_update(CLI::App& app, RunWithMaster run, int& rc) {
    auto args = std::make_shared<Args>();
    auto* c = app.add_subcommand(
        "firmware-update",
        "Update the firmware over FoE: identity check, BOOT, write, INIT, restart, revision check");
    c->add_option("file", args->file, "Firmware image (fwimage build)")->required()->check(CLI::ExistingFile);
    c->add_option("-p,--position", args->slave, "Slave position (or station address with --station)")
        ->capture_default_str();
    c->add_flag("-s,--station", args->station, "--position is a station address");
    c->add_option("--password", args->password, "FoE password")->capture_default_str();
    c->add_option("-n,--name", args->name, "File name on the slave (default: the device name, 0x1008)");
    c->add_flag("-f,--force", args->force,
                "Send even an image that is not valid or not for this device, or to a drive switched on");
    c->add_flag("--no-boot", args->no_boot,
                "Write in the current state instead of BOOT (the device should refuse)");
    c->add_flag("--progress", args->progress, "Show progress also when stderr is not a terminal");
    c->add_option("--restart-timeout", args->restart_timeout_ms, "Milliseconds to wait for the restart")
        ->check(CLI::Range(100u, 600000u))
        ->capture_default_str();
    c->callback([args, run, &rc] {
        auto image = std::make_shared<Image>();
        if ((rc = load_image(*args, *image)) != kExitOk) return;
        rc = run([args, image](master::Master& m) { return firmware_update(m, *args, *image); });
    });
}

}  // namespace ecatctl
