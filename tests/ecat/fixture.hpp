#pragma once
// Test fixture: an emulated ESC (esc::Esc) with a ManualClock, the slave stack on its PDI, and the test
// acting as the master by building EtherCAT frames and handing them to esc.process_frame().
#include <gtest/gtest.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "ecat/stack.hpp"
#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "esc/wire/datagram.hpp"
#include "od/device.hpp"
#include "od/dictionary.hpp"

namespace ecat::test {

// AL status (0x0130) bit 4: the error indication (ETG.1000.6 5.3.2).
inline constexpr uint16_t kErr = 0x10;

// A minimal master: one datagram per frame, position addressing of the single slave.
class Master {
  public:
    void attach(esc::Esc& e) { esc_ = &e; }

    // Sends one datagram; data is replaced by what came back. Returns the working counter.
    uint16_t exchange(esc::Command cmd, uint32_t address, std::span<uint8_t> data);
    uint16_t write(uint16_t ado, std::span<const uint8_t> data);
    uint16_t read(uint16_t ado, std::span<uint8_t> data);
    template <typename T>
    uint16_t wr(uint16_t ado, T v) {
        uint8_t b[sizeof(T)];
        for (std::size_t i = 0; i < sizeof(T); ++i)
            b[i] = static_cast<uint8_t>(static_cast<uint64_t>(v) >> (8 * i));
        return write(ado, b);
    }
    template <typename T>
    T rd(uint16_t ado) {
        uint8_t b[sizeof(T)] = {};
        read(ado, b);
        uint64_t v = 0;
        for (std::size_t i = 0; i < sizeof(T); ++i)
            v |= static_cast<uint64_t>(b[i]) << (8 * i);
        return static_cast<T>(v);
    }
    uint16_t lrw(uint32_t logical, std::span<uint8_t> data) {
        return exchange(esc::Command::LRW, logical, data);
    }

  private:
    esc::Esc* esc_ = nullptr;
    uint8_t index_ = 0;
};

// The application side: records what the stack told it; loops outputs back into inputs on each cycle.
class RecordingApp : public Application {
  public:
    uint16_t check_transition(od::AlState from, od::AlState to) override {
        (void)from;
        return to == veto_state ? veto_code : 0;
    }
    void on_state_change(od::AlState from, od::AlState to) override { changes.push_back({from, to}); }
    void on_cycle(uint64_t now_ns) override {
        ++cycles;
        last_cycle_ns = now_ns;
        if (cycle_hook) cycle_hook();
    }
    void on_outputs_lost() override { ++outputs_lost; }
    void on_restart() override { ++restarts; }

    std::vector<std::pair<od::AlState, od::AlState>> changes;
    int cycles = 0;
    uint64_t last_cycle_ns = 0;
    int outputs_lost = 0;
    int restarts = 0;
    od::AlState veto_state = static_cast<od::AlState>(0);
    uint16_t veto_code = 0;
    std::function<void()> cycle_hook;
};

// Sample device: standard mailbox 128/128 at 0x1000/0x1080, bootstrap 256/256 at 0x1000/0x1100,
// SM2 outputs at 0x1200, SM3 inputs at 0x1300; RxPDO 0x1600 = {0x6040 u16, 0x607A i32},
// TxPDO 0x1A00 = {0x6041 u16, 0x6064 i32}; 0x2000:01..08 BOOL mappable both ways for bit-level maps.
od::Dictionary make_dictionary();
od::DeviceDescription make_description();

constexpr uint16_t kSm2Start = 0x1200;
constexpr uint16_t kSm3Start = 0x1300;
constexpr uint32_t kLogical = 0x00010000;

class StackTest : public ::testing::Test {
  protected:
    StackTest();
    ~StackTest() override;
    void SetUp() override { start(); }
    // (Re)builds ESC and stack (after a test changed dict / desc).
    void start();
    // One runtime pass: ESC timers, then the stack.
    void poll();
    void advance(uint64_t ns);
    // AL control write from the master followed by a poll.
    void request(uint16_t control);
    uint16_t al_status() { return master.rd<uint16_t>(0x0130); }
    uint16_t al_code() { return master.rd<uint16_t>(0x0134); }

    void configure_sm(unsigned n, uint16_t start, uint16_t length, uint8_t control, bool enable);
    void configure_fmmu(unsigned n, uint32_t logical, uint16_t length, uint16_t physical, uint8_t type);
    void configure_mailbox();
    void configure_bootstrap_mailbox();
    // Configures SM2/SM3 and FMMU0/1 (outputs at kLogical, inputs right behind them).
    void configure_process_data(uint16_t rx_bytes, uint16_t tx_bytes, uint8_t sm2_control = 0x64);

    void go_preop();
    void go_safeop();
    void go_op();
    // One LRW over the outputs and inputs; returns WKC. in receives the inputs.
    uint16_t exchange_pd(std::span<const uint8_t> out, std::span<uint8_t> in);

    // Mailbox as the master sees it.
    void mbx_write(std::span<const uint8_t> message);
    std::vector<uint8_t> mbx_read();  // empty if SM1 was empty (WKC 0)
    std::vector<uint8_t> mbx_message(uint8_t type, uint8_t counter, std::span<const uint8_t> payload,
                                     uint16_t address = 0, uint8_t channel = 0);

    esc::ManualClock clock;
    std::unique_ptr<esc::Esc> esc;
    od::Dictionary dict;
    od::DeviceDescription desc;
    RecordingApp app;
    std::unique_ptr<Stack> stack;
    Master master;
    uint16_t rx_bytes = 6;
    uint16_t tx_bytes = 6;
};

}  // namespace ecat::test
