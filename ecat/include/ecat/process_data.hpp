#pragma once
// Process-data copy plan (ETG.1000.6, PDO mapping and SyncManager PDO assignment objects): built from the PDO
// assignment of each process-data SM (0x1C10 + n: 0x1C12 outputs/SM2, 0x1C13 inputs/SM3 on a device with a
// mailbox) and the mapping objects it assigns (of that direction as the object model declares it, wherever
// their index lies) when the slave enters Safe-Op, then used every cycle to copy bit-exactly between the SM
// buffers and the dictionary's value storage, allocating nothing. A device with several SMs of one direction
// (EL1252's three input SMs, two output SMs of an IO terminal) gets one image per direction in which each
// SM's part starts on a byte of its own (SmImage), in SM order.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "od/dictionary.hpp"

namespace ecat {

struct PdoCopy {
    uint8_t* storage = nullptr;  // entry value in the dictionary's image (nullptr: padding, never copied)
    uint32_t bit_offset = 0;     // position in the SM buffer
    uint16_t bits = 0;
    const od::Entry* entry = nullptr;  // the entry mapped (for the application's view of the mapping)
};

// One SM's part of a direction's image: SM number, first byte in the image, length in bytes (the SM length
// its assignment gives).
struct SmImage {
    unsigned sm = 0;
    std::size_t offset = 0;
    std::size_t bytes = 0;
};

class ProcessData {
  public:
    static constexpr std::size_t kMaxEntries = 256;  // per direction
    static constexpr std::size_t kMaxSms = 16;       // SMs of an ESC (ESC datasheet, 0x0800 + 8n)
    static constexpr uint16_t kRxAssign = 0x1C12;
    static constexpr uint16_t kTxAssign = 0x1C13;
    // The PDO assignment object of SM n (ETG.1000.6: 0x1C10 + n); a device without mailbox assigns its
    // process data to SM0/SM1 (0x1C10/0x1C11).
    static constexpr uint16_t assign_index(unsigned sm) { return static_cast<uint16_t>(0x1C10 + sm); }
    static constexpr unsigned kNoSm = 0xFF;

    explicit ProcessData(od::Dictionary& dictionary);

    // Reads the assignment and mapping objects and builds both plans. Returns 0 or the AL status code:
    // 0x0025 invalid output mapping (RxPDO side) / 0x0024 invalid input mapping (TxPDO side).
    // outputs_sms / inputs_sms: the SyncManagers of the two directions in SM order (empty: none).
    uint16_t build(std::span<const unsigned> outputs_sms, std::span<const unsigned> inputs_sms);
    // One SM per direction (kNoSm: none, no process data in that direction).
    uint16_t build(unsigned outputs_sm = 2, unsigned inputs_sm = 3);
    void clear();

    // Each SM's part of the output (RxPDO) and input (TxPDO) images, in SM order.
    std::span<const SmImage> rx_sms() const { return {rx_sms_.data(), rx_sms_.size()}; }
    std::span<const SmImage> tx_sms() const { return {tx_sms_.data(), tx_sms_.size()}; }

    // The whole image of a direction, every SM's part (each rounded up to bytes).
    std::size_t rx_bits() const { return rx_bits_; }
    std::size_t tx_bits() const { return tx_bits_; }
    std::size_t rx_bytes() const { return (rx_bits_ + 7) / 8; }
    std::size_t tx_bytes() const { return (tx_bits_ + 7) / 8; }
    std::span<const PdoCopy> rx_plan() const { return {rx_.data(), rx_.size()}; }
    std::span<const PdoCopy> tx_plan() const { return {tx_.data(), tx_.size()}; }

    // Output image (every output SM's part) -> dictionary.
    void outputs_to_dictionary(std::span<const uint8_t> sm2) const;
    // Dictionary -> input image (every input SM's part); bits not mapped keep their value.
    void dictionary_to_inputs(std::span<uint8_t> sm3) const;
    // Input image -> dictionary for the entries of one input SM's part: an input SM over the ESC's registers,
    // whose values are the registers' (ecat::inputs_on_registers).
    void inputs_to_dictionary(std::span<const uint8_t> sm3, const SmImage& part) const;

    // Copies n bits from src (starting at bit src_bit) to dst (starting at bit dst_bit), LSB first.
    static void copy_bits(const uint8_t* src, std::size_t src_bit, uint8_t* dst, std::size_t dst_bit,
                          std::size_t n);

  private:
    // Appends SM `sm`'s PDOs to `plan`, from bit `bits` on (advanced past them).
    uint16_t build_sm(unsigned sm, bool rx, std::vector<PdoCopy>& plan, std::size_t& bits);

    od::Dictionary& dict_;
    std::vector<PdoCopy> rx_;
    std::vector<PdoCopy> tx_;
    std::vector<SmImage> rx_sms_;
    std::vector<SmImage> tx_sms_;
    std::size_t rx_bits_ = 0;
    std::size_t tx_bits_ = 0;
};

}  // namespace ecat
