// Values printed by their CoE data type, taken from the SDO information service (ETG.1000.6 §5.6.3):
// `upload` without --type, complete access split per subindex, and `pd` by PDO entry.
#include <cstdio>

#include "cmd_verbs.hpp"

namespace ecatctl {

bool print_described_upload(master::SdoClient& sdo, uint16_t index, uint8_t sub, bool complete_access,
                            std::span<const uint8_t> data) {
    if (!complete_access) {
        auto e = sdo.entry_description(index, sub, 0);
        if (!e) return false;
        std::printf("%s\n", format_typed(e->data_type, e->bit_length, data).c_str());
        return true;
    }
    auto od = sdo.object_description(index);
    if (!od) return false;
    if (od->object_code == 7) {  // a VAR: complete access is a plain access
        auto e = sdo.entry_description(index, 0, 0);
        if (!e) return false;
        std::printf("0x%04x:00 %s = %s\n", index, e->name.c_str(),
                    format_typed(e->data_type, e->bit_length, data).c_str());
        return true;
    }
    std::vector<EntryView> entries;
    if (describe_entries(sdo, index, od->max_subindex, entries) != master::Error::Ok || entries.empty())
        return false;
    // An ARRAY carries as many entries as subindex 0 says.
    if (od->object_code == 8 && sub == 0 && !data.empty()) {
        const unsigned count = data[0];
        std::erase_if(entries, [&](const EntryView& e) { return e.subindex > count; });
    }
    for (const auto& part : split_complete_access(entries, sub, data))
        std::printf("0x%04x:%02x %s = %s\n", index, part.entry.subindex, part.entry.name.c_str(),
                    format_typed(part.entry.data_type, part.entry.bit_length, part.value).c_str());
    return true;
}

void write_described_upload_json(util::JsonWriter& w, master::SdoClient& sdo, uint16_t index, uint8_t sub,
                                 bool complete_access, std::span<const uint8_t> data) {
    auto one = [&](const EntryView& e, std::span<const uint8_t> v) {
        w.begin_object()
            .member("subindex", e.subindex)
            .member("name", e.name)
            .member("type", esi_type_name(e.data_type))
            .member("bit_length", e.bit_length)
            .key("value");
        write_typed_json(w, e.data_type, e.bit_length, v);
        w.end_object();
    };
    // No description (the slave has no SDO information): an empty list, the bytes say the rest.
    w.key("entries").begin_array();
    if (!complete_access) {
        if (auto e = sdo.entry_description(index, sub, 0))
            one({sub, e->data_type, e->bit_length, e->access, e->name}, data);
    } else if (auto od = sdo.object_description(index)) {
        if (od->object_code == 7) {  // a VAR: complete access is a plain access
            if (auto e = sdo.entry_description(index, 0, 0))
                one({0, e->data_type, e->bit_length, e->access, e->name}, data);
        } else if (std::vector<EntryView> entries;
                   describe_entries(sdo, index, od->max_subindex, entries) == master::Error::Ok) {
            // An ARRAY carries as many entries as subindex 0 says.
            if (od->object_code == 8 && sub == 0 && !data.empty()) {
                const unsigned count = data[0];
                std::erase_if(entries, [&](const EntryView& e) { return e.subindex > count; });
            }
            for (const auto& part : split_complete_access(entries, sub, data))
                one(part.entry, part.value);
        }
    }
    w.end_array();
}

namespace {

void print_image(const char* title, const std::vector<SyncView>& syncs, bool output,
                 std::span<const uint8_t> image) {
    std::size_t bit = 0;
    bool any = false;
    for (const auto& sv : syncs) {
        if (sv.output != output) continue;
        for (const auto& p : sv.pdos)
            for (const auto& e : p.entries) {
                if (e.index != 0) {
                    if (!any) std::printf("%s\n", title);
                    any = true;
                    const auto v = extract_bits(image, bit, e.bit_length);
                    std::printf("  0x%04x:%02x %s = %s\n", e.index, e.subindex, e.name.c_str(),
                                format_typed(e.data_type, e.bit_length, v).c_str());
                }
                bit += e.bit_length;
            }
        bit = (bit + 7) / 8 * 8;  // the next SM's data starts on a byte of the image (the session's layout)
    }
}

}  // namespace

void print_pd_entries(const std::vector<SyncView>& syncs, std::span<const uint8_t> outputs,
                      std::span<const uint8_t> inputs) {
    print_image("outputs by entry:", syncs, true, outputs);
    print_image("inputs by entry:", syncs, false, inputs);
}

}  // namespace ecatctl
