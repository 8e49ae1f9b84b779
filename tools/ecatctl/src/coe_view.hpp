#pragma once
// What a slave says about its objects and its process data, read over CoE only (SDO upload and the SDO
// information service, ETG.1000.6 §5.6.2/§5.6.3): typed values, entries of an object, the live PDO
// assignment and mapping. Shared by upload, pd, pdos, cstruct and xml. Needs no slave internals.
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "master/coe.hpp"
#include "util/json.hpp"

namespace ecatctl {

// CoE basic data types (ETG.1000.6 Table 63) the verbs decode.
namespace dtype {
constexpr uint16_t Boolean = 0x0001, Integer8 = 0x0002, Integer16 = 0x0003, Integer32 = 0x0004,
                   Unsigned8 = 0x0005, Unsigned16 = 0x0006, Unsigned32 = 0x0007, Real32 = 0x0008,
                   VisibleString = 0x0009, OctetString = 0x000A, UnicodeString = 0x000B, Real64 = 0x0011,
                   Integer64 = 0x0015, Unsigned64 = 0x001B;
}

// "UINT16", "REAL32", ... as ESI files name them (ETG.2000); "" for a type code not in the table.
std::string_view esi_type_name(uint16_t data_type);

// A value of data_type with bit_length bits (bit_length < 8: the low bits of data[0]) as text:
// integers "0x0237 (567)", REAL32/REAL64 the number, VISIBLE_STRING the text (up to the first NUL),
// anything else a hex byte string.
std::string format_typed(uint16_t data_type, uint16_t bit_length, std::span<const uint8_t> data);

// The same value as a JSON value: integers as numbers (BOOLEAN and bit types too), REAL32/REAL64 as numbers,
// VISIBLE_STRING as a string, anything else (octet strings, unknown types) as a string of hex bytes
// "0a 1b ...".
void write_typed_json(util::JsonWriter& w, uint16_t data_type, uint16_t bit_length,
                      std::span<const uint8_t> data);

// Text -> bytes of data_type (integers, REAL32/REAL64, strings); nullopt if it does not fit.
std::optional<std::vector<uint8_t>> encode_typed(uint16_t data_type, uint16_t bit_length,
                                                 const std::vector<std::string>& words);

struct EntryView {
    uint8_t subindex = 0;
    uint16_t data_type = 0;
    uint16_t bit_length = 0;
    uint16_t access = 0;
    std::string name;
};

// The entries of an object as SDO information describes them (subindices that do not exist are skipped).
master::Error describe_entries(master::SdoClient& sdo, uint16_t index, uint8_t max_subindex,
                               std::vector<EntryView>& out);

// A complete-access image (from_sub 0 or 1) split into one (entry, bytes) per subindex, laid out as the
// slave lays it out: subindex 0 takes 16 bits, byte-sized entries start on a byte, bit entries are packed.
// Entries past the image's end are left out.
struct CaPart {
    EntryView entry;
    std::vector<uint8_t> value;
};
std::vector<CaPart> split_complete_access(const std::vector<EntryView>& entries, uint8_t from_sub,
                                          std::span<const uint8_t> image);

// ---- PDOs --------------------------------------------------------------------------------------------

struct PdoEntryView {
    uint16_t index = 0;  // 0: a gap
    uint8_t subindex = 0;
    uint8_t bit_length = 0;
    uint16_t data_type = 0;  // from SDO information, 0 if unknown
    std::string name;
};

struct PdoView {
    uint16_t index = 0;
    std::string name;
    std::vector<PdoEntryView> entries;
};

struct SyncView {
    uint8_t sm = 0;
    bool output = false;  // RxPDOs (master -> slave)
    std::vector<PdoView> pdos;
    unsigned bits() const;
};

// The live process-data configuration: which SMs carry process data (0x1C00, else SM2 outputs and SM3
// inputs), their assignments (0x1C1n) and each assigned PDO's mapping, with names from SDO information
// when names is set (a slave without SDO information gives empty names).
master::Error read_pdo_config(master::SdoClient& sdo, std::vector<SyncView>& out, bool names = true);

// Reads a value of up to 64 bits at bit offset `bit` of a process image.
std::vector<uint8_t> extract_bits(std::span<const uint8_t> image, std::size_t bit, std::size_t bits);

}  // namespace ecatctl
