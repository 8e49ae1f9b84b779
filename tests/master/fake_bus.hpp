#pragma once
// A deliberately small model of a line of ESCs for the master's unit tests: position/station/broadcast
// register access, the SII EEPROM interface with both read sizes, busy and not-acknowledged phases, and
// an AL state machine that follows AL control (optionally refusing). It exists so that the master's
// corner cases can be forced; the real esc::Esc is exercised by the in-process test and the integration
// tests.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <deque>
#include <span>
#include <vector>

#include "esc/link.hpp"
#include "util/le.hpp"

namespace fake {

// Little-endian access: the project's helpers (util/le.hpp).
using util::get16;
using util::put16;

struct Slave {
    std::vector<uint8_t> mem = std::vector<uint8_t>(0x2000, 0);
    std::vector<uint16_t> eeprom;     // words
    uint16_t beyond_eeprom = 0xFFFF;  // what reads past the image return
    bool read_size8 = false;
    int busy_polls = 0;          // the next command stays busy for this many status reads
    int nacks = 0;               // the next n commands fail with bit 13
    bool write_protect = false;  // every SII write fails with bit 14
    int busy_left = 0;
    bool pending = false;
    // AL: refuse requests for this state with this code (0 = accept everything).
    uint8_t refuse_state = 0;
    uint16_t refuse_code = 0;
    bool al_ignore = false;  // AL status never follows AL control
    int al_writes = 0;
    std::vector<uint16_t> al_control_log;

    Slave() {
        mem[0] = 0x04;
        put16(&mem[0x0130], 0x0001);
    }

    uint16_t reg16(uint16_t a) const { return get16(&mem[a]); }

    void after_write(uint16_t ado, std::size_t len) {
        auto touched = [&](uint16_t a) { return ado <= a && a < ado + len; };
        if (touched(0x0502)) sii_command();
        if (touched(0x0120)) al_control();
    }
    void before_read(uint16_t ado, std::size_t len) {
        if (ado <= 0x0502 && 0x0502 < ado + len && pending) {
            if (busy_left > 0) {
                --busy_left;
            } else {
                finish_sii();
            }
        }
    }
    void sii_command() {
        uint16_t ctl = reg16(0x0502);
        const uint16_t cmd = ctl & 0x0700;
        const auto status = static_cast<uint16_t>(read_size8 ? 0x0040 : 0);
        if (cmd == 0) {
            put16(&mem[0x0502], static_cast<uint16_t>(read_size8 ? 0x0040 : 0));  // clears errors
            return;
        }
        put16(&mem[0x0502], static_cast<uint16_t>(status | cmd | (ctl & 1) | 0x8000));
        pending = true;
        busy_left = busy_polls;
    }
    void finish_sii() {
        pending = false;
        uint16_t ctl = reg16(0x0502);
        const uint16_t cmd = ctl & 0x0700;
        uint16_t status = static_cast<uint16_t>(read_size8 ? 0x0040 : 0);
        const uint32_t addr = get16(&mem[0x0504]) | (static_cast<uint32_t>(get16(&mem[0x0506])) << 16);
        if (nacks > 0) {
            --nacks;
            status |= 0x2000;
        } else if (cmd == 0x0100) {
            const int words = read_size8 ? 4 : 2;
            for (int i = 0; i < words; ++i) {
                const uint32_t w = addr + static_cast<uint32_t>(i);
                put16(&mem[0x0508 + 2 * i], w < eeprom.size() ? eeprom[w] : beyond_eeprom);
            }
        } else if (cmd == 0x0200) {
            if (!(ctl & 1) || write_protect) {
                status |= 0x4000;
            } else if (addr < eeprom.size()) {
                eeprom[addr] = get16(&mem[0x0508]);
            } else {
                status |= 0x2000;
            }
        } else {
            status |= 0x2000;
        }
        put16(&mem[0x0502], status);
    }
    void al_control() {
        ++al_writes;
        const uint16_t ctl = reg16(0x0120);
        al_control_log.push_back(ctl);
        if (al_ignore) return;
        uint16_t st = reg16(0x0130);
        if ((st & 0x10) && !(ctl & 0x10)) return;  // error pending and not acknowledged: ignore
        const uint8_t want = ctl & 0x0F;
        if (refuse_state != 0 && want == refuse_state) {
            put16(&mem[0x0130], static_cast<uint16_t>((st & 0x0F) | 0x10));
            put16(&mem[0x0134], refuse_code);
            return;
        }
        put16(&mem[0x0130], want);
        put16(&mem[0x0134], 0);
    }
};

// Frames go through every slave in order, as on a line; the reply is queued for receive().
class Bus final : public esc::Link {
  public:
    std::vector<Slave> slaves;
    int drop_next = 0;        // replies to lose
    bool echo_stale = false;  // before each reply, deliver a stale copy of the previous one
    bool echo_own = false;    // deliver the unprocessed request first (as a loop with no ESC would)
    std::size_t frames = 0;
    std::vector<std::vector<uint8_t>> sent;

    explicit Bus(std::size_t n) : slaves(n) {}

    int fd() const override { return -1; }
    std::size_t receive(std::span<uint8_t> buf) override {
        if (queue_.empty()) return 0;
        auto f = std::move(queue_.front());
        queue_.pop_front();
        const std::size_t n = std::min(buf.size(), f.size());
        std::memcpy(buf.data(), f.data(), n);
        return n;
    }
    bool send(std::span<const uint8_t> frame) override {
        ++frames;
        std::vector<uint8_t> f(frame.begin(), frame.end());
        sent.push_back(f);
        if (echo_own) queue_.push_back(f);
        process(f);
        if (drop_next > 0) {
            --drop_next;
            return true;
        }
        if (echo_stale && !last_.empty()) queue_.push_back(last_);
        last_ = f;
        queue_.push_back(std::move(f));
        return true;
    }

  private:
    void process(std::vector<uint8_t>& f) {
        if (f.size() < 16 || f[12] != 0x88 || f[13] != 0xA4 || slaves.empty()) return;
        f[6] |= 0x02;
        const std::size_t end = 16 + (get16(&f[14]) & 0x07FF);
        std::size_t pos = 16;
        while (pos + 12 <= end) {
            uint8_t* h = &f[pos];
            const uint8_t cmd = h[0];
            const std::size_t len = get16(h + 6) & 0x07FF;
            if (pos + 12 + len > end) break;
            uint8_t* data = h + 10;
            uint8_t* wkc = data + len;
            for (Slave& s : slaves) {
                const uint16_t adp = get16(h + 2);
                const uint16_t ado = get16(h + 4);
                bool hit = false, wr = false, rd = false;
                switch (cmd) {
                    case 1:
                        hit = adp == 0;
                        rd = true;
                        put16(h + 2, static_cast<uint16_t>(adp + 1));
                        break;
                    case 2:
                        hit = adp == 0;
                        wr = true;
                        put16(h + 2, static_cast<uint16_t>(adp + 1));
                        break;
                    case 4:
                        hit = adp == s.reg16(0x0010);
                        rd = true;
                        break;
                    case 5:
                        hit = adp == s.reg16(0x0010);
                        wr = true;
                        break;
                    case 7:
                        hit = true;
                        rd = true;
                        put16(h + 2, static_cast<uint16_t>(adp + 1));
                        break;
                    case 8:
                        hit = true;
                        wr = true;
                        put16(h + 2, static_cast<uint16_t>(adp + 1));
                        break;
                    default:
                        break;
                }
                if (!hit || ado + len > s.mem.size()) continue;
                if (rd) {
                    s.before_read(ado, len);
                    for (std::size_t i = 0; i < len; ++i)
                        data[i] = static_cast<uint8_t>(cmd == 7 ? data[i] | s.mem[ado + i] : s.mem[ado + i]);
                }
                if (wr) {
                    std::memcpy(&s.mem[ado], data, len);
                    s.after_write(ado, len);
                }
                put16(wkc, static_cast<uint16_t>(get16(wkc) + 1));
            }
            pos += 12 + len;
            if (!(get16(h + 6) & 0x8000)) break;
        }
    }
    std::deque<std::vector<uint8_t>> queue_;
    std::vector<uint8_t> last_;
};

}  // namespace fake
