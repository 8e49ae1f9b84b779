#include "coe/emergency.hpp"

#include <algorithm>

#include "wire.hpp"

namespace coe {

namespace {
constexpr uint16_t kErrorRegister = 0x1001;
constexpr uint8_t kGenericBit = 0x01;
}  // namespace

Emergency::Emergency(od::Dictionary* dict, std::size_t capacity)
    : dict_(dict), capacity_(std::clamp<std::size_t>(capacity, 1, kQueueCapacity)) {}

Emergency::Message Emergency::encode(uint16_t error_code, uint8_t error_register,
                                     std::span<const uint8_t> mfr) {
    Message m{};
    wire::put_coe_header(m.data(), wire::Service::Emergency);
    wire::put16(m.data() + 2, error_code);
    m[4] = error_register;
    std::size_t n = std::min<std::size_t>(mfr.size(), 5);
    std::copy_n(mfr.begin(), n, m.begin() + 5);
    return m;
}

bool Emergency::active(uint16_t error_code) const {
    return std::any_of(active_.begin(), active_.begin() + static_cast<std::ptrdiff_t>(active_count_),
                       [&](const Active& a) { return a.code == error_code; });
}

void Emergency::update_register() {
    uint8_t reg = 0;
    for (std::size_t i = 0; i < active_count_; ++i)
        reg = static_cast<uint8_t>(reg | active_[i].bits);
    // CiA 301 (0x1001): the generic bit (bit 0) is signalled at any error situation.
    if (active_count_ != 0) reg = static_cast<uint8_t>(reg | kGenericBit);
    register_ = reg;
    if (dict_ != nullptr && dict_->find(kErrorRegister, 0) != nullptr)
        dict_->set<uint8_t>(kErrorRegister, 0, reg);
}

void Emergency::raise(uint16_t error_code, uint8_t register_bits, std::span<const uint8_t> mfr) {
    bool found = false;
    for (std::size_t i = 0; i < active_count_; ++i) {
        if (active_[i].code == error_code) {
            active_[i].bits = static_cast<uint8_t>(active_[i].bits | register_bits);
            found = true;
        }
    }
    if (!found && active_count_ < kMaxActive) active_[active_count_++] = Active{error_code, register_bits};
    update_register();
    push(encode(error_code, register_, mfr));
}

void Emergency::clear(uint16_t error_code) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < active_count_; ++i)
        if (active_[i].code != error_code) active_[n++] = active_[i];
    if (n == active_count_) return;
    active_count_ = n;
    update_register();
    if (active_count_ == 0) push(encode(0x0000, register_, {}));
}

void Emergency::clear_all() {
    if (active_count_ == 0) return;
    active_count_ = 0;
    update_register();
    push(encode(0x0000, register_, {}));
}

void Emergency::send(uint16_t error_code, uint8_t error_register, std::span<const uint8_t> mfr) {
    push(encode(error_code, error_register, mfr));
}

void Emergency::push(const Message& m) {
    if (count_ == capacity_) {
        head_ = (head_ + 1) % capacity_;
        --count_;
        ++dropped_;
    }
    queue_[(head_ + count_) % capacity_] = m;
    ++count_;
}

void Emergency::pop() {
    if (count_ == 0) return;
    head_ = (head_ + 1) % capacity_;
    --count_;
}

void Emergency::discard_all() {
    head_ = 0;
    count_ = 0;
}

}  // namespace coe
