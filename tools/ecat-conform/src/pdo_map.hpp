#pragma once
// The process-data image of the current PDO assignment, entry by entry (read over CoE), for the pd and
// cia402 groups.
#include "sdo_util.hpp"

namespace conform {

struct MappedEntry {
    uint16_t pdo = 0;
    uint16_t index = 0;
    uint8_t sub = 0;
    uint8_t bits = 0;
    std::size_t bit_offset = 0;  // within the SM's image
};

struct PdoMap {
    std::vector<MappedEntry> outputs, inputs;
    const MappedEntry* find_out(uint16_t i, uint8_t s = 0) const {
        for (const auto& e : outputs)
            if (e.index == i && e.sub == s) return &e;
        return nullptr;
    }
    const MappedEntry* find_in(uint16_t i, uint8_t s = 0) const {
        for (const auto& e : inputs)
            if (e.index == i && e.sub == s) return &e;
        return nullptr;
    }
};

// The entries of the PDOs that `assign` (0x1C10 + n) assigns, appended to `out` from bit `off` of the
// direction's image on.
inline master::Error read_assign(Context& ctx, uint16_t assign, std::vector<MappedEntry>& out,
                                 std::size_t off = 0) {
    auto n = ctx.upload_uint(assign, 0);
    if (!n) return n.error();
    for (uint8_t i = 1; i <= *n; ++i) {
        auto p = ctx.upload_uint(assign, i);
        if (!p) return p.error();
        auto m = ctx.upload_uint(static_cast<uint16_t>(*p), 0);
        if (!m) return m.error();
        for (uint8_t k = 1; k <= *m; ++k) {
            auto e = ctx.upload_uint(static_cast<uint16_t>(*p), k);
            if (!e) return e.error();
            MappedEntry me{static_cast<uint16_t>(*p), static_cast<uint16_t>(*e >> 16),
                           static_cast<uint8_t>(*e >> 8), static_cast<uint8_t>(*e), off};
            off += me.bits;
            if (me.index) out.push_back(me);
        }
    }
    return master::Error::Ok;
}

// Outputs and inputs as the session lays them out: each process-data SM with data in SM order, from the byte
// where the previous one ended (ETG.1000.6: SM n's PDOs are those of 0x1C10 + n); without a session's
// layout, SM2 and SM3.
inline master::Error read_map(Context& ctx, PdoMap& m) {
    m.outputs.clear();
    m.inputs.clear();
    if (!ctx.pds) {
        if (auto e = read_assign(ctx, 0x1C12, m.outputs); e != master::Error::Ok) return e;
        return read_assign(ctx, 0x1C13, m.inputs);
    }
    std::size_t out_bytes = 0, in_bytes = 0;
    for (const master::ProcessDataSm& sm : ctx.pds->layout().sms) {
        if (!sm.length) continue;
        std::size_t& at = sm.outputs ? out_bytes : in_bytes;
        // An SM without assignment object (the session took its PDOs from the SII) has no entries to name.
        const auto e = read_assign(ctx, static_cast<uint16_t>(0x1C10 + sm.index),
                                   sm.outputs ? m.outputs : m.inputs, 8 * at);
        const bool absent = e == master::Error::SdoAbort &&
                            (ctx.sdo->last_abort() == 0x06020000 || ctx.sdo->last_abort() == 0x06090011);
        if (e != master::Error::Ok && !absent) return e;
        at += sm.length;
    }
    return master::Error::Ok;
}

inline uint64_t image_get(std::span<const uint8_t> img, const MappedEntry& e) {
    uint64_t v = 0;
    for (unsigned b = 0; b < e.bits; ++b) {
        const std::size_t bit = e.bit_offset + b;
        if (bit / 8 < img.size() && (img[bit / 8] >> (bit % 8)) & 1) v |= uint64_t{1} << b;
    }
    return v;
}
inline void image_set(std::span<uint8_t> img, const MappedEntry& e, uint64_t v) {
    for (unsigned b = 0; b < e.bits; ++b) {
        const std::size_t bit = e.bit_offset + b;
        if (bit / 8 >= img.size()) return;
        if ((v >> b) & 1)
            img[bit / 8] = static_cast<uint8_t>(img[bit / 8] | (1u << (bit % 8)));
        else
            img[bit / 8] = static_cast<uint8_t>(img[bit / 8] & ~(1u << (bit % 8)));
    }
}
// Outputs set to what the slave's objects hold now (so the first exchange changes nothing).
inline void prefill_outputs(Context& ctx, const PdoMap& m) {
    for (const auto& e : m.outputs)
        if (auto v = ctx.upload_uint(e.index, e.sub)) image_set(ctx.pds->outputs(), e, *v);
}

}  // namespace conform
