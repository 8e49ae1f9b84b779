#pragma once
// CoE emergency (service 1, ETG.1000.6 Emergency): the drive glue raises and clears errors here; the error
// register 0x1001 follows the active errors; messages wait in a bounded queue until CoeServer::poll()
// sends them through the mailbox.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "od/dictionary.hpp"

namespace coe {

class Emergency {
  public:
    static constexpr std::size_t kMessageSize = 10;  // CoE header 2 + code 2 + register 1 + data 5
    static constexpr std::size_t kQueueCapacity = 16;
    static constexpr std::size_t kMaxActive = 32;
    using Message = std::array<uint8_t, kMessageSize>;

    // dict may be null (no 0x1001 to maintain). capacity is clamped to 1..kQueueCapacity.
    explicit Emergency(od::Dictionary* dict = nullptr, std::size_t capacity = 8);

    // An error occurred: remember it as active, OR its register bits into 0x1001 (the bits the error table
    // gives: the MAXPOS firmware specification, Table 8-141, sets e.g. only the motion bit for 0x8611, so no
    // generic bit is forced) and queue an emergency carrying the new register value. mfr: up to 5
    // manufacturer-specific bytes (more are cut, fewer are zero-padded).
    void raise(uint16_t error_code, uint8_t register_bits, std::span<const uint8_t> mfr = {});
    // The error went away: recompute 0x1001; when no error is left, queue the "no error" emergency
    // (code 0x0000). Clearing an error that is not active does nothing.
    void clear(uint16_t error_code);
    // All errors went away (fault reset): one "no error" emergency if any was active.
    void clear_all();
    // Queue one message as given, without touching the active set or 0x1001: for an application that keeps
    // its own error register (drive::EventSink passes the new 0x1001 value with every raise/clear).
    void send(uint16_t error_code, uint8_t error_register, std::span<const uint8_t> mfr = {});

    uint8_t error_register() const { return register_; }
    bool active(uint16_t error_code) const;
    std::size_t active_count() const { return active_count_; }

    // Queue access for the sender. A full queue drops its oldest message (the newest state matters most).
    bool empty() const { return count_ == 0; }
    std::size_t pending() const { return count_; }
    std::size_t dropped() const { return dropped_; }
    const Message& front() const { return queue_[head_]; }
    void pop();
    void discard_all();

    // Encodes one emergency (with its CoE header) into out.
    static Message encode(uint16_t error_code, uint8_t error_register, std::span<const uint8_t> mfr);

  private:
    struct Active {
        uint16_t code;
        uint8_t bits;
    };
    void push(const Message& m);
    void update_register();

    od::Dictionary* dict_;
    std::size_t capacity_;
    std::array<Message, kQueueCapacity> queue_{};
    std::size_t head_ = 0;
    std::size_t count_ = 0;
    std::size_t dropped_ = 0;
    std::array<Active, kMaxActive> active_{};
    std::size_t active_count_ = 0;
    uint8_t register_ = 0;
};

}  // namespace coe
