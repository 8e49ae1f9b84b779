// (2) A whole slave in process, as `ecat-slave` runs it: the emulated ESC, the ecat stack (AL state
// machine, mailbox, process data, SyncManager and DC events), the CoE server with PDO validators and the
// diagnosis history, the FoE server (over an in-memory firmware sink, memory_sink.hpp) and the CiA 402
// drive with its simulated motor, all on the drive's dictionary and the SII built from it. Input: a
// sequence of frames, each [time byte][16-bit length][frame]; the time byte moves the clock (10 us steps)
// before the frame goes through the ESC, then the ESC's timers and the firmware run, as the runtime does.
// Checked: nothing crashes (ASan, UBSan) and the stack's AL state is always one of the five.
// Per input: the dictionary (built once) is put back into its built state (fuzz_support.hpp); the ESC, the
// stack, the servers and the drive are built afresh.
#include <algorithm>
#include <memory>
#include <vector>

#include "coe/diagnosis.hpp"
#include "coe/events.hpp"
#include "coe/pdo_validation.hpp"
#include "coe/sdo_server.hpp"
#include "drive/drive.hpp"
#include "ecat/application.hpp"
#include "ecat/stack.hpp"
#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "esi/sii.hpp"
#include "foe/image.hpp"
#include "foe/server.hpp"
#include "fuzz_support.hpp"
#include "harnesses.hpp"
#include "maxpos/maxpos.hpp"
#include "memory_sink.hpp"

namespace fuzz::slave {
namespace {

// What every input starts from, built once: the description, the dictionary (put back into its built state
// for each input, fuzz_support.hpp), the SII rendered from it and a firmware image.
struct Prototype {
    od::DeviceDescription desc = maxpos::description();
    PristineDictionary dict{maxpos::dictionary(desc), [](od::Dictionary& d) {
                                (void)drive::commission(d, maxpos::drive_objects());
                                coe::install_pdo_validators(d);
                            }};
    std::vector<uint8_t> sii;
    std::vector<uint8_t> image;
    Prototype() {
        sii = esi::build_sii(desc, dict.fresh());
        std::vector<uint8_t> payload(200, 0x5A);
        image = foe::build_image(payload, foe::ImageIdentity::from(desc.identity), desc.identity.revision);
    }
};
Prototype& prototype() {
    static Prototype p;
    return p;
}

// The firmware around the drive: runs a drive cycle for each stack cycle, as device::Device does.
class DriveApp final : public ecat::Application, public drive::EventSink {
  public:
    void attach(drive::Drive* d, coe::EventReporter* e) {
        drive_ = d;
        events_ = e;
    }
    void on_cycle(uint64_t now_ns) override {
        int64_t dt = 0;
        if (last_ != 0 && now_ns > last_)
            dt = std::min<int64_t>(static_cast<int64_t>(now_ns - last_), 100'000'000);
        last_ = now_ns;
        if (drive_) drive_->cycle(static_cast<int64_t>(now_ns), dt);
    }
    void on_outputs_lost() override {
        if (drive_) drive_->connection_lost();
    }
    void raise(uint16_t code, uint8_t reg, const std::array<uint8_t, 5>& mfr) override {
        if (events_) events_->raise(code, reg, mfr);
    }
    void clear(uint16_t code, uint8_t reg) override {
        if (events_) events_->clear(code, reg);
    }
    void diag(drive::Severity, uint16_t, std::string_view) override {}

  private:
    drive::Drive* drive_ = nullptr;
    coe::EventReporter* events_ = nullptr;
    uint64_t last_ = 0;
};

}  // namespace

int fuzz_one(const uint8_t* data, std::size_t size) {
    Prototype& proto = prototype();
    esc::ManualClock clock;
    clock.set(1'000'000'000);
    esc::Esc esc(esc::EscConfig{}, clock);
    od::Dictionary& dict = proto.dict.fresh();
    DriveApp app;
    ecat::Stack stack(esc, dict, proto.desc, app, [&esc] { return esc.irq(); });
    coe::CoeServer coe(dict, [&stack] { return stack.state(); });
    coe::DiagnosisHistory diag(dict, &coe.emergency());
    coe::EventReporter events(coe.emergency(), &diag, [&clock] { return clock.now_ns(); });
    MemorySink sink(foe::ImageIdentity::from(proto.desc.identity), proto.desc.identity.device_name,
                    64u << 10);
    sink.install(0, proto.image);
    foe::ServerConfig fc = foe::ServerConfig::from(proto.desc);
    fc.commit_in_thread = false;
    foe::FoeServer foe(sink, fc);
    stack.add_handler(coe);
    stack.add_handler(foe);
    drive::Drive drive(dict, &app, maxpos::drive_objects());
    app.attach(&drive, &events);
    esc.load_eeprom(proto.sii);
    stack.poll(clock.now_ns());

    for_each_frame(data, size, [&](uint8_t dt, std::vector<uint8_t>& frame) {
        clock.advance(uint64_t{dt} * 10'000);
        esc.tick();
        stack.poll(clock.now_ns());
        esc.process_frame(frame);
        esc.tick();
        stack.poll(clock.now_ns());
        const auto s = static_cast<uint8_t>(stack.state());
        FUZZ_CHECK(s == 1 || s == 2 || s == 3 || s == 4 || s == 8);
    });
    app.attach(nullptr, nullptr);
    return 0;
}

}  // namespace fuzz::slave
