#pragma once
// The object model: every object and subindex of the device, declared once (od/src/), read by everyone
// else: the SDO server and SDO information (coe/), PDO mapping (ecat/ process data), the SII image and ESI
// file (esi/), and the drive application (drive/).
//
// Values live in one little-endian byte image (no per-access allocation); Ref<T> gives the drive and the
// process-data layer a zero-cost typed handle to one entry.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "od/types.hpp"

namespace od {

// A declared numeric value (default, minimum, maximum). monostate = not given.
using Number = std::variant<std::monostate, int64_t, uint64_t, double>;

// One named value of an enumerated entry (ESI EnumInfo).
struct NamedValue {
    int64_t value = 0;
    std::string text;
};

struct Entry {
    uint16_t index = 0;
    uint8_t subindex = 0;
    std::string name;
    DataType type = DataType::Unsigned8;
    uint16_t bit_length = 0;  // for strings: capacity in bits
    // A shorter length the device's own PDOs map this integer entry with (its low-order bits), 0 if none: the
    // "compact" PDOs of vendor files (Beckhoff EJ7047: 0x7000:11, UDINT, mapped with 16 bits). A mapping
    // entry of this length is accepted as one of bit_length is.
    uint16_t pdo_bit_length = 0;
    uint16_t access = access::RO;  // od::access bits, including PDO mappability, backup and settings
    Number default_value;
    Number minimum;
    Number maximum;
    std::string default_string;  // VISIBLE_STRING / OCTET_STRING default
    std::string unit;            // e.g. "inc", "rpm", "mNm", "ms"; empty if none
    // The values the entry takes, each with its name, if it is an enumeration (od/value_names.hpp); empty
    // otherwise.
    std::vector<NamedValue> enumeration;
    // Storage (filled by the dictionary): byte offset of this entry's value in the value image.
    std::size_t offset = 0;

    bool readable(AlState s) const;
    bool writable(AlState s) const;
    bool rx_mappable() const { return access & access::RxPdo; }
    bool tx_mappable() const { return access & access::TxPdo; }
    bool backup() const { return access & access::Backup; }
    std::size_t byte_size() const { return (bit_length + 7u) / 8u; }
    // A mapping entry may map this entry with `bits` bits: its own length, or the device's compact one.
    bool mappable_with(unsigned bits) const {
        return bits == bit_length || (bits != 0 && bits == pdo_bit_length);
    }
};

struct Object {
    uint16_t index = 0;
    ObjectCode code = ObjectCode::Var;
    std::string name;
    DataType type = DataType::Unsigned8;  // VAR: its type; ARRAY: element type; RECORD: record type code
    std::vector<Entry> entries;           // sorted by subindex; VAR has exactly one (subindex 0)
    // Process data: the direction of the PDO this mapping object describes, or of the SM this assignment
    // object (0x1C10 + n) assigns to; None for every other object. Declared by the product where it knows
    // it (an ESI's RxPdo/TxPdo element and Sm kinds, an ENI's); left None, Dictionary::add() gives the
    // standard ranges' (standard_pdo_direction). Nothing else tells a PDO's direction by its index.
    PdoDirection direction = PdoDirection::None;
    bool is_pdo_mapping() const { return direction != PdoDirection::None && !is_assignment_index(index); }
    bool is_pdo_assignment() const { return direction != PdoDirection::None && is_assignment_index(index); }
    bool rx() const { return direction == PdoDirection::Rx; }
    uint8_t max_subindex() const { return entries.empty() ? 0 : entries.back().subindex; }
    const Entry* entry(uint8_t sub) const;
};

// Typed handle to one entry's storage. T must match the entry's byte size.
template <typename T>
class Ref {
  public:
    Ref() = default;
    explicit Ref(uint8_t* p) : p_(p) {}
    T get() const {
        T v;
        std::memcpy(&v, p_, sizeof(T));
        return v;
    }
    void set(T v) { std::memcpy(p_, &v, sizeof(T)); }
    bool valid() const { return p_ != nullptr; }

  private:
    uint8_t* p_ = nullptr;
};

class Dictionary {
  public:
    // Called before a master write (SDO or PDO configuration) is committed; a non-Ok result vetoes it.
    using Validator = std::function<Status(const Entry&, std::span<const uint8_t> value)>;
    // Called after a value changed through write() or set()/set_raw() (not through Ref<T>).
    using Listener = std::function<void(const Entry&)>;
    // Called before a value is read through read(), so computed values can be refreshed.
    using ReadHook = std::function<void(const Entry&)>;

    Dictionary();
    ~Dictionary();
    Dictionary(Dictionary&&) noexcept;
    Dictionary& operator=(Dictionary&&) noexcept;

    // ---- Declaration (used by od/ itself to declare the device) -----------------------------------
    // Adds an object; entries' offsets are assigned here. Throws std::logic_error on a duplicate index.
    void add(Object object);

    // ---- Lookup -----------------------------------------------------------------------------------
    const Object* find(uint16_t index) const;
    const Entry* find(uint16_t index, uint8_t sub) const;
    std::span<const Object> objects() const;  // sorted by index

    // ---- Master-side access (SDO, complete access, PDO configuration) ------------------------------
    // Checks access rights for the AL state, runs read hooks, copies the current value to out.
    // length receives the number of bytes of the value (strings: their current length).
    // NoObject / NoSubindex; WriteOnly if never readable; WrongState if not readable in `state` (Init and
    // Bootstrap: always); LengthTooHigh if `out` is too small (length then says how much is needed).
    Status read(uint16_t index, uint8_t sub, AlState state, std::span<uint8_t> out, std::size_t& length);
    // Checks access rights, length, limits and validators; commits; notifies listeners.
    // ReadOnly if never writable, WrongState if not writable in `state`; LengthTooHigh/LengthTooLow for a
    // scalar of the wrong size (strings: up to their capacity, shorter allowed); ValueTooHigh/ValueTooLow
    // outside minimum/maximum (BOOLEAN: 0/1; REAL NaN: InvalidValue); then the first non-Ok validator.
    Status write(uint16_t index, uint8_t sub, AlState state, std::span<const uint8_t> value);

    // ---- Device-side access (no access-rights check; type, length and limits are still checked) -----
    Status set_raw(uint16_t index, uint8_t sub, std::span<const uint8_t> value);
    std::span<const uint8_t> raw(uint16_t index, uint8_t sub) const;  // current value bytes

    // Extension: type, length and limit check of a would-be value without committing it (no access
    // rights, no validators). Used by the parameter store to validate a whole file before applying it.
    Status check(uint16_t index, uint8_t sub, std::span<const uint8_t> value) const;
    // Extension: the declared default's bytes (strings: the default's length); empty if no such entry.
    std::span<const uint8_t> default_raw(uint16_t index, uint8_t sub) const;
    // Extension: writable view of a scalar entry's storage for the process-data copy (no checks, no
    // listeners, like Ref<T>); empty for strings and missing entries. Valid until the next add().
    std::span<uint8_t> mutable_raw(uint16_t index, uint8_t sub);

    template <typename T>
    T get(uint16_t index, uint8_t sub) const {
        auto r = raw(index, sub);
        if (r.size() < sizeof(T))
            throw std::out_of_range("od::Dictionary::get: no such entry or size mismatch");
        T v;
        std::memcpy(&v, r.data(), sizeof(T));
        return v;
    }
    template <typename T>
    Status set(uint16_t index, uint8_t sub, T value) {
        static_assert(std::is_trivially_copyable_v<T>);
        uint8_t b[sizeof(T)];
        std::memcpy(b, &value, sizeof(T));
        return set_raw(index, sub, std::span<const uint8_t>(b, sizeof(T)));
    }
    // Zero-cost handle; throws std::out_of_range if the entry does not exist or its size is not sizeof(T).
    template <typename T>
    Ref<T> ref(uint16_t index, uint8_t sub) {
        return Ref<T>(storage(index, sub, sizeof(T)));
    }

    // ---- Hooks ------------------------------------------------------------------------------------
    // owner: whoever installs the hook and may be destroyed before the dictionary; it calls
    // remove_hooks(this) in its destructor. Hooks installed without an owner live as long as the dictionary.
    void add_validator(uint16_t index, Validator v, const void* owner = nullptr);
    void add_listener(uint16_t index, Listener l, const void* owner = nullptr);
    void add_read_hook(uint16_t index, ReadHook h, const void* owner = nullptr);
    // Removes every hook installed with this owner (nullptr: nothing).
    void remove_hooks(const void* owner);

    // Every entry back to its declared default. Listeners are not called.
    void reset_to_defaults();

  private:
    uint8_t* storage(uint16_t index, uint8_t sub, std::size_t size);
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace od
