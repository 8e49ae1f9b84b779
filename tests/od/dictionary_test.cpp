// The dictionary engine: declaration, lookup, access rules per AL state, lengths, limits, strings, Ref<T>,
// validators, listeners, read hooks, defaults.
#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <limits>
#include <vector>

#include "od/dictionary.hpp"

using namespace od;

namespace {

Entry entry(uint8_t sub, DataType t, uint16_t acc, Number def = {}, Number min = {}, Number max = {}) {
    Entry e;
    e.subindex = sub;
    // Appended, not "e" + std::to_string(sub): GCC 12 at -O3 misjudges the insert at position 0 of
    // operator+(const char*, string&&) as an overlapping memcpy (-Werror=restrict, GCC bug 105651).
    e.name = "e";
    e.name += std::to_string(sub);
    e.type = t;
    e.access = acc;
    e.default_value = def;
    e.minimum = min;
    e.maximum = max;
    return e;
}

Object var(uint16_t index, Entry e) {
    Object o;
    o.index = index;
    o.code = ObjectCode::Var;
    o.name = "var";
    o.type = e.type;
    o.entries.push_back(std::move(e));
    return o;
}

Entry string_entry(uint8_t sub, DataType t, uint16_t acc, std::string def, uint16_t capacity) {
    Entry e = entry(sub, t, acc);
    e.default_string = std::move(def);
    e.bit_length = static_cast<uint16_t>(8 * capacity);
    return e;
}

// A small dictionary with one object of each kind the drive uses.
Dictionary sample() {
    Dictionary d;
    d.add(var(0x1000, entry(0, DataType::Unsigned32, access::RO, uint64_t{0x00020192})));
    d.add(
        var(0x6040, entry(0, DataType::Unsigned16, access::RW | access::RxPdo | access::TxPdo, uint64_t{0})));
    d.add(var(0x6060, entry(0, DataType::Integer8, access::RW, int64_t{8}, int64_t{-4}, int64_t{10})));
    d.add(var(0x607A, entry(0, DataType::Integer32, access::RW, int64_t{-5})));
    d.add(var(0x6402, entry(0, DataType::Unsigned16, access::RW_PreOp | access::Backup, uint64_t{10},
                            uint64_t{1}, uint64_t{10})));
    d.add(var(0x2000, entry(0, DataType::Unsigned32, access::WO, uint64_t{0})));
    d.add(var(0x2001, entry(0, DataType::Real32, access::RW, 1.5, -2.0, 2.0)));
    d.add(var(0x2002, entry(0, DataType::Boolean, access::RW, uint64_t{0})));
    d.add(var(0x2003, entry(0, DataType::Unsigned64, access::RW, uint64_t{0xFFFFFFFFFFFFFFFFull})));
    d.add(var(0x2004, entry(0, DataType::Integer64, access::RW, int64_t{-1}, int64_t{-100}, int64_t{100})));
    d.add(var(0x1008, string_entry(0, DataType::VisibleString, access::RO, "MAXPOS", 6)));
    d.add(var(0x2005, string_entry(0, DataType::VisibleString, access::RW, "abc", 8)));
    d.add(var(0x2006, string_entry(0, DataType::OctetString, access::RW, "", 4)));
    Object rec;
    rec.index = 0x1018;
    rec.code = ObjectCode::Record;
    rec.name = "Identity Object";
    rec.type = DataType::Identity;
    rec.entries.push_back(entry(4, DataType::Unsigned32, access::RO, uint64_t{44}));
    rec.entries.push_back(entry(1, DataType::Unsigned32, access::RO, uint64_t{0xFB}));
    rec.entries.push_back(entry(2, DataType::Unsigned32, access::RO, uint64_t{2}));
    d.add(std::move(rec));
    return d;
}

std::vector<uint8_t> bytes(std::initializer_list<uint8_t> b) {
    return b;
}

}  // namespace

TEST(OdTypes, BitSizesAndClasses) {
    EXPECT_EQ(bit_size(DataType::Boolean), 1);
    EXPECT_EQ(bit_size(DataType::Integer8), 8);
    EXPECT_EQ(bit_size(DataType::Unsigned16), 16);
    EXPECT_EQ(bit_size(DataType::Real32), 32);
    EXPECT_EQ(bit_size(DataType::Unsigned64), 64);
    EXPECT_EQ(bit_size(DataType::VisibleString), 0);
    EXPECT_EQ(bit_size(DataType::Identity), 0);
    EXPECT_TRUE(is_signed(DataType::Integer64));
    EXPECT_FALSE(is_signed(DataType::Unsigned8));
    EXPECT_TRUE(is_real(DataType::Real64));
    EXPECT_TRUE(is_string(DataType::OctetString));
    EXPECT_FALSE(is_string(DataType::Unsigned32));
    EXPECT_EQ(to_string(DataType::Unsigned32), "UDINT");
    EXPECT_EQ(to_string(Status::CannotStore), "data cannot be transferred or stored");
    EXPECT_EQ(to_string(Status::Ok), "ok");
}

TEST(OdDictionary, LookupIsSortedAndSubindexZeroIsHighestSubindex) {
    Dictionary d = sample();
    auto objs = d.objects();
    for (std::size_t i = 1; i < objs.size(); ++i)
        EXPECT_LT(objs[i - 1].index, objs[i].index);
    const Object* id = d.find(0x1018);
    ASSERT_NE(id, nullptr);
    EXPECT_EQ(id->max_subindex(), 4);
    ASSERT_NE(id->entry(0), nullptr);
    EXPECT_EQ(id->entry(0)->type, DataType::Unsigned8);
    EXPECT_EQ(d.get<uint8_t>(0x1018, 0), 4);  // highest subindex, not the number of entries (3)
    EXPECT_EQ(id->entry(3), nullptr);
    EXPECT_EQ(d.find(0x1018, 3), nullptr);
    EXPECT_EQ(d.find(0x1234), nullptr);
    EXPECT_EQ(d.get<uint32_t>(0x1018, 1), 0xFBu);
    EXPECT_EQ(d.find(0x1018, 1)->index, 0x1018);
}

TEST(OdDictionary, DeclarationErrorsThrow) {
    Dictionary d = sample();
    EXPECT_THROW(d.add(var(0x1000, entry(0, DataType::Unsigned8, access::RO))), std::logic_error);
    // default out of range of the type
    EXPECT_THROW(d.add(var(0x3000, entry(0, DataType::Unsigned8, access::RO, uint64_t{256}))),
                 std::logic_error);
    // default outside declared limits
    EXPECT_THROW(
        d.add(var(0x3001, entry(0, DataType::Integer16, access::RW, int64_t{5}, int64_t{6}, int64_t{9}))),
        std::logic_error);
    // string default longer than its capacity
    EXPECT_THROW(d.add(var(0x3002, string_entry(0, DataType::VisibleString, access::RO, "toolong", 3))),
                 std::logic_error);
    // VAR must have exactly subindex 0
    EXPECT_THROW(d.add(var(0x3003, entry(1, DataType::Unsigned8, access::RO))), std::logic_error);
    // ARRAY elements share the array's type; sub-index 0 is UNSIGNED8
    Object arr;
    arr.index = 0x3004;
    arr.code = ObjectCode::Array;
    arr.type = DataType::Unsigned16;
    arr.entries.push_back(entry(1, DataType::Unsigned16, access::RO));
    arr.entries.push_back(entry(2, DataType::Unsigned32, access::RO));
    EXPECT_THROW(d.add(arr), std::logic_error);
    arr.entries[1].type = DataType::Unsigned16;
    arr.entries.push_back(entry(0, DataType::Unsigned16, access::RO, uint64_t{2}));
    EXPECT_THROW(d.add(arr), std::logic_error);
    arr.entries.pop_back();
    arr.entries.push_back(entry(2, DataType::Unsigned16, access::RO));  // duplicate subindex
    EXPECT_THROW(d.add(arr), std::logic_error);
    arr.entries.pop_back();
    d.add(arr);
    EXPECT_EQ(d.get<uint8_t>(0x3004, 0), 2);
    EXPECT_EQ(d.find(0x3000), nullptr);
}

TEST(OdDictionary, UnknownObjectAndSubindex) {
    Dictionary d = sample();
    std::array<uint8_t, 8> out{};
    std::size_t len = 99;
    EXPECT_EQ(d.read(0x5555, 0, AlState::PreOp, out, len), Status::NoObject);
    EXPECT_EQ(len, 0u);
    EXPECT_EQ(d.read(0x1018, 7, AlState::PreOp, out, len), Status::NoSubindex);
    EXPECT_EQ(d.write(0x5555, 0, AlState::PreOp, bytes({1})), Status::NoObject);
    EXPECT_EQ(d.write(0x1000, 1, AlState::PreOp, bytes({1})), Status::NoSubindex);
    EXPECT_EQ(d.set_raw(0x5555, 0, bytes({1})), Status::NoObject);
    EXPECT_TRUE(d.raw(0x5555, 0).empty());
}

TEST(OdDictionary, AccessRulesPerAlState) {
    Dictionary d = sample();
    std::array<uint8_t, 8> out{};
    std::size_t len = 0;
    const auto u16 = bytes({5, 0});
    // read-only
    EXPECT_EQ(d.write(0x1000, 0, AlState::PreOp, bytes({0, 0, 0, 0})), Status::ReadOnly);
    EXPECT_EQ(d.write(0x1000, 0, AlState::Op, bytes({0, 0, 0, 0})), Status::ReadOnly);
    EXPECT_EQ(d.read(0x1000, 0, AlState::SafeOp, out, len), Status::Ok);
    // write-only
    EXPECT_EQ(d.read(0x2000, 0, AlState::PreOp, out, len), Status::WriteOnly);
    EXPECT_EQ(d.write(0x2000, 0, AlState::Op, bytes({1, 2, 3, 4})), Status::Ok);
    // rw in every state
    for (AlState s : {AlState::PreOp, AlState::SafeOp, AlState::Op})
        EXPECT_EQ(d.write(0x6040, 0, s, u16), Status::Ok);
    // rw only in Pre-Op
    EXPECT_EQ(d.write(0x6402, 0, AlState::PreOp, u16), Status::Ok);
    EXPECT_EQ(d.write(0x6402, 0, AlState::SafeOp, u16), Status::WrongState);
    EXPECT_EQ(d.write(0x6402, 0, AlState::Op, u16), Status::WrongState);
    EXPECT_EQ(d.read(0x6402, 0, AlState::Op, out, len), Status::Ok);
    // no CoE access in Init and Bootstrap
    EXPECT_EQ(d.read(0x1000, 0, AlState::Init, out, len), Status::WrongState);
    EXPECT_EQ(d.read(0x1000, 0, AlState::Boot, out, len), Status::WrongState);
    EXPECT_EQ(d.write(0x6040, 0, AlState::Init, u16), Status::WrongState);
    EXPECT_EQ(d.write(0x6040, 0, AlState::Boot, u16), Status::WrongState);
    const Entry* e = d.find(0x6402, 0);
    EXPECT_TRUE(e->writable(AlState::PreOp));
    EXPECT_FALSE(e->writable(AlState::SafeOp));
    EXPECT_TRUE(e->readable(AlState::Op));
    EXPECT_TRUE(e->backup());
    EXPECT_TRUE(d.find(0x6040, 0)->rx_mappable());
    EXPECT_TRUE(d.find(0x6040, 0)->tx_mappable());
    EXPECT_FALSE(d.find(0x1000, 0)->rx_mappable());
}

TEST(OdDictionary, ScalarLengthsMustMatch) {
    Dictionary d = sample();
    EXPECT_EQ(d.write(0x6040, 0, AlState::Op, bytes({1})), Status::LengthTooLow);
    EXPECT_EQ(d.write(0x6040, 0, AlState::Op, bytes({1, 2, 3})), Status::LengthTooHigh);
    EXPECT_EQ(d.write(0x6040, 0, AlState::Op, bytes({})), Status::LengthTooLow);
    EXPECT_EQ(d.set_raw(0x607A, 0, bytes({1, 2})), Status::LengthTooLow);
    EXPECT_EQ(d.get<uint16_t>(0x6040, 0), 0);  // nothing committed
    EXPECT_EQ(d.write(0x2003, 0, AlState::Op, bytes({1, 2, 3, 4, 5, 6, 7, 8})), Status::Ok);
    EXPECT_EQ(d.get<uint64_t>(0x2003, 0), 0x0807060504030201ull);
}

TEST(OdDictionary, RangeChecksSignedUnsignedRealBoolean) {
    Dictionary d = sample();
    // INTEGER8 -4...10
    EXPECT_EQ(d.write(0x6060, 0, AlState::Op, bytes({11})), Status::ValueTooHigh);
    EXPECT_EQ(d.write(0x6060, 0, AlState::Op, bytes({0xFB})), Status::ValueTooLow);  // -5
    EXPECT_EQ(d.write(0x6060, 0, AlState::Op, bytes({0xFC})), Status::Ok);           // -4
    EXPECT_EQ(d.get<int8_t>(0x6060, 0), -4);
    EXPECT_EQ(d.write(0x6060, 0, AlState::Op, bytes({10})), Status::Ok);
    // UNSIGNED16 1...10 (Pre-Op)
    EXPECT_EQ(d.write(0x6402, 0, AlState::PreOp, bytes({0, 0})), Status::ValueTooLow);
    EXPECT_EQ(d.write(0x6402, 0, AlState::PreOp, bytes({11, 0})), Status::ValueTooHigh);
    EXPECT_EQ(d.write(0x6402, 0, AlState::PreOp, bytes({0, 1})), Status::ValueTooHigh);  // 256
    // INTEGER64 -100...100
    int64_t v = -101;
    std::array<uint8_t, 8> b{};
    std::memcpy(b.data(), &v, 8);
    EXPECT_EQ(d.write(0x2004, 0, AlState::Op, b), Status::ValueTooLow);
    v = 100;
    std::memcpy(b.data(), &v, 8);
    EXPECT_EQ(d.write(0x2004, 0, AlState::Op, b), Status::Ok);
    // REAL32 -2...2, NaN refused
    float f = 2.5f;
    std::array<uint8_t, 4> fb{};
    std::memcpy(fb.data(), &f, 4);
    EXPECT_EQ(d.write(0x2001, 0, AlState::Op, fb), Status::ValueTooHigh);
    f = -2.5f;
    std::memcpy(fb.data(), &f, 4);
    EXPECT_EQ(d.write(0x2001, 0, AlState::Op, fb), Status::ValueTooLow);
    f = std::numeric_limits<float>::quiet_NaN();
    std::memcpy(fb.data(), &f, 4);
    EXPECT_EQ(d.write(0x2001, 0, AlState::Op, fb), Status::InvalidValue);
    EXPECT_FLOAT_EQ(d.get<float>(0x2001, 0), 1.5f);
    // BOOLEAN: 0 or 1
    EXPECT_EQ(d.write(0x2002, 0, AlState::Op, bytes({2})), Status::ValueTooHigh);
    EXPECT_EQ(d.write(0x2002, 0, AlState::Op, bytes({1})), Status::Ok);
    // device-side writes are range-checked too
    EXPECT_EQ(d.set<int8_t>(0x6060, 0, 42), Status::ValueTooHigh);
    EXPECT_EQ(d.check(0x6060, 0, bytes({42})), Status::ValueTooHigh);
    EXPECT_EQ(d.check(0x6060, 0, bytes({3})), Status::Ok);
}

TEST(OdDictionary, StringsUpToCapacityShorterAllowed) {
    Dictionary d = sample();
    std::array<uint8_t, 16> out{};
    std::size_t len = 0;
    ASSERT_EQ(d.read(0x2005, 0, AlState::PreOp, out, len), Status::Ok);
    EXPECT_EQ(len, 3u);
    EXPECT_EQ(std::string(out.begin(), out.begin() + 3), "abc");
    EXPECT_EQ(d.find(0x2005, 0)->bit_length, 64);
    const std::string full = "12345678";
    EXPECT_EQ(d.write(0x2005, 0, AlState::Op, std::span(reinterpret_cast<const uint8_t*>(full.data()), 8)),
              Status::Ok);
    ASSERT_EQ(d.read(0x2005, 0, AlState::Op, out, len), Status::Ok);
    EXPECT_EQ(len, 8u);
    const std::string longer = "123456789";
    EXPECT_EQ(d.write(0x2005, 0, AlState::Op, std::span(reinterpret_cast<const uint8_t*>(longer.data()), 9)),
              Status::LengthTooHigh);
    const std::string shorter = "xy";
    EXPECT_EQ(d.write(0x2005, 0, AlState::Op, std::span(reinterpret_cast<const uint8_t*>(shorter.data()), 2)),
              Status::Ok);
    auto r = d.raw(0x2005, 0);
    EXPECT_EQ(std::string(r.begin(), r.end()), "xy");
    // an empty octet string reads as zero bytes
    ASSERT_EQ(d.read(0x2006, 0, AlState::Op, out, len), Status::Ok);
    EXPECT_EQ(len, 0u);
    // a string is not a Ref<T>
    EXPECT_THROW(d.ref<uint32_t>(0x2006, 0), std::out_of_range);
    EXPECT_TRUE(d.mutable_raw(0x2006, 0).empty());
}

TEST(OdDictionary, ReadIntoTooSmallBufferReportsLength) {
    Dictionary d = sample();
    std::array<uint8_t, 2> small{};
    std::size_t len = 0;
    EXPECT_EQ(d.read(0x1000, 0, AlState::PreOp, small, len), Status::LengthTooHigh);
    EXPECT_EQ(len, 4u);
}

TEST(OdDictionary, RefIsZeroCostViewOfTheImage) {
    Dictionary d = sample();
    Ref<uint16_t> cw = d.ref<uint16_t>(0x6040, 0);
    ASSERT_TRUE(cw.valid());
    EXPECT_FALSE(Ref<uint16_t>().valid());
    cw.set(0x000F);
    EXPECT_EQ(d.get<uint16_t>(0x6040, 0), 0x000F);
    std::array<uint8_t, 2> out{};
    std::size_t len = 0;
    ASSERT_EQ(d.read(0x6040, 0, AlState::Op, out, len), Status::Ok);
    EXPECT_EQ(out[0], 0x0F);
    ASSERT_EQ(d.write(0x6040, 0, AlState::Op, bytes({0x80, 0x00})), Status::Ok);
    EXPECT_EQ(cw.get(), 0x0080);
    Ref<int32_t> tp = d.ref<int32_t>(0x607A, 0);
    EXPECT_EQ(tp.get(), -5);
    EXPECT_THROW(d.ref<uint32_t>(0x6040, 0), std::out_of_range);  // size mismatch
    EXPECT_THROW(d.ref<uint16_t>(0x7777, 0), std::out_of_range);
    // moving the dictionary keeps handles valid (the image belongs to the moved impl)
    Dictionary moved = std::move(d);
    cw.set(0x1234);
    EXPECT_EQ(moved.get<uint16_t>(0x6040, 0), 0x1234);
    auto span = moved.mutable_raw(0x6040, 0);
    ASSERT_EQ(span.size(), 2u);
    span[0] = 0x55;
    EXPECT_EQ(cw.get(), 0x1255);
}

TEST(OdDictionary, ValidatorsVetoAndListenersFollowCommits) {
    Dictionary d = sample();
    int validated = 0, notified = 0;
    d.add_validator(0x6040, [&](const Entry& e, std::span<const uint8_t> v) {
        ++validated;
        EXPECT_EQ(e.index, 0x6040);
        return v[1] == 0xFF ? Status::InvalidValue : Status::Ok;
    });
    d.add_listener(0x6040, [&](const Entry& e) {
        ++notified;
        EXPECT_EQ(e.subindex, 0);
    });
    EXPECT_EQ(d.write(0x6040, 0, AlState::Op, bytes({1, 0xFF})), Status::InvalidValue);
    EXPECT_EQ(d.get<uint16_t>(0x6040, 0), 0);
    EXPECT_EQ(notified, 0);
    EXPECT_EQ(d.write(0x6040, 0, AlState::Op, bytes({1, 0})), Status::Ok);
    EXPECT_EQ(validated, 2);
    EXPECT_EQ(notified, 1);
    // device-side set: listeners yes, validators no
    EXPECT_EQ(d.set<uint16_t>(0x6040, 0, 0xFF00), Status::Ok);
    EXPECT_EQ(validated, 2);
    EXPECT_EQ(notified, 2);
    // Ref<T>: neither
    d.ref<uint16_t>(0x6040, 0).set(7);
    EXPECT_EQ(notified, 2);
    // a failed length check runs no validator
    EXPECT_EQ(d.write(0x6040, 0, AlState::Op, bytes({1})), Status::LengthTooLow);
    EXPECT_EQ(validated, 2);
    EXPECT_THROW(d.add_listener(0x7777, [](const Entry&) {}), std::out_of_range);
}

TEST(OdDictionary, RemoveHooksTakesOnlyTheOwnersHooks) {
    Dictionary d = sample();
    int mine = 0, other = 0, anonymous = 0;
    const int owner_a = 0, owner_b = 0;  // any two distinct addresses
    d.add_validator(
        0x6040, [&](const Entry&, std::span<const uint8_t>) { return Status::InvalidValue; }, &owner_a);
    d.add_listener(
        0x6040, [&](const Entry&) { ++mine; }, &owner_a);
    d.add_read_hook(
        0x6040, [&](const Entry&) { ++mine; }, &owner_a);
    d.add_listener(
        0x6040, [&](const Entry&) { ++other; }, &owner_b);
    d.add_listener(0x6040, [&](const Entry&) { ++anonymous; });
    EXPECT_EQ(d.write(0x6040, 0, AlState::Op, bytes({1, 0})), Status::InvalidValue);
    d.remove_hooks(&owner_a);
    d.remove_hooks(nullptr);  // removes nothing
    EXPECT_EQ(d.write(0x6040, 0, AlState::Op, bytes({1, 0})), Status::Ok);
    uint8_t out[2];
    std::size_t n = 0;
    EXPECT_EQ(d.read(0x6040, 0, AlState::Op, out, n), Status::Ok);
    EXPECT_EQ(mine, 0);
    EXPECT_EQ(other, 1);
    EXPECT_EQ(anonymous, 1);
}

TEST(OdDictionary, ReadHookRefreshesBeforeTheCopy) {
    Dictionary d = sample();
    int32_t source = 0;
    auto pos = d.ref<int32_t>(0x607A, 0);
    d.add_read_hook(0x607A, [&](const Entry&) { pos.set(source); });
    source = 123456;
    std::array<uint8_t, 4> out{};
    std::size_t len = 0;
    ASSERT_EQ(d.read(0x607A, 0, AlState::Op, out, len), Status::Ok);
    int32_t v;
    std::memcpy(&v, out.data(), 4);
    EXPECT_EQ(v, 123456);
}

TEST(OdDictionary, ResetToDefaults) {
    Dictionary d = sample();
    auto cw = d.ref<uint16_t>(0x6040, 0);
    cw.set(99);
    ASSERT_EQ(d.set<int8_t>(0x6060, 0, 3), Status::Ok);
    const std::string s = "zz";
    ASSERT_EQ(d.set_raw(0x2005, 0, std::span(reinterpret_cast<const uint8_t*>(s.data()), 2)), Status::Ok);
    d.reset_to_defaults();
    EXPECT_EQ(cw.get(), 0);  // handles survive the reset
    EXPECT_EQ(d.get<int8_t>(0x6060, 0), 8);
    auto r = d.raw(0x2005, 0);
    EXPECT_EQ(std::string(r.begin(), r.end()), "abc");
    auto def = d.default_raw(0x607A, 0);
    ASSERT_EQ(def.size(), 4u);
    EXPECT_EQ(def[0], 0xFB);  // -5
}

TEST(OdDictionary, ImageIsLittleEndian) {
    Dictionary d = sample();
    auto r = d.raw(0x1000, 0);
    ASSERT_EQ(r.size(), 4u);
    EXPECT_EQ(r[0], 0x92);
    EXPECT_EQ(r[1], 0x01);
    EXPECT_EQ(r[2], 0x02);
    EXPECT_EQ(r[3], 0x00);
}
