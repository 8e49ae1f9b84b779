#pragma once
// Non-volatile parameters: every entry with the Backup flag, saved to one file in a state directory.
//
// The file is replaced atomically (temp file, fsync, rename, fsync of the directory), so a crash or power
// cut at any moment leaves either the old set or the new one. load() validates the whole file (header,
// CRC-32, identity, every record against the dictionary) before it applies anything: a bad, truncated or
// foreign file is reported and the defaults stay.
//
// File layout (little-endian):
//   0  char[8]  magic "SECATPRM"          24 u32 number of records
//   8  u16      format version (1)        28 u32 payload bytes
//  10  u16      header bytes (40)         32 u32 CRC-32 of the payload
//  12  u32      vendor id                 36 u32 CRC-32 of header bytes 0...35
//  16  u32      product code
//  20  u32      revision number
//  40  records: u16 index, u8 subindex, u8 0, u16 data type, u16 length, length bytes of value
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "od/dictionary.hpp"

namespace od {

// Signatures of the store (0x1010) and restore (0x1011) commands (CiA 301).
constexpr uint32_t kSignatureSave = 0x65766173;  // "save", little-endian
constexpr uint32_t kSignatureLoad = 0x64616F6C;  // "load", little-endian

// Which entries a store/restore command covers (0x2110/0x2111 subindex 1 all, 2 communication, 6 axis).
enum class StoreScope : uint8_t {
    All,            // every Backup entry
    Communication,  // 0x1000...0x1FFF
    Application,    // 0x2000...0xFFFF (manufacturer and profile objects: the "axis" parameters)
};

bool in_scope(StoreScope scope, uint16_t index);

class ParameterStore {
  public:
    static constexpr uint16_t kFormatVersion = 1;
    static constexpr std::size_t kHeaderBytes = 40;

    explicit ParameterStore(std::filesystem::path state_dir, std::string file_name = "parameters.bin");

    const std::filesystem::path& file() const { return file_; }

    struct LoadResult {
        bool found = false;       // a file was there
        bool applied = false;     // its values are now in the dictionary
        std::size_t entries = 0;  // number of entries applied
        std::string error;        // why a file that was there was rejected (empty if applied or none)
    };
    // Applies the stored set to `dict` (all or nothing). No file: found == false, defaults stay.
    LoadResult load(Dictionary& dict) const;

    // Stores the Backup entries of `scope` with their current values; the entries outside `scope` keep
    // the values of the current file (or are left out, i.e. default). Returns "" or the error text.
    std::string save(const Dictionary& dict, StoreScope scope = StoreScope::All);

    // CiA 301 "restore default parameters": the stored values of `scope` are dropped so the defaults apply
    // at the next start; the running values do not change. Returns "" or the error text.
    std::string restore_defaults(const Dictionary& dict, StoreScope scope = StoreScope::All);

    // Removes parameters.bin.tmp if an interrupted save left it behind (never valid: the rename is the
    // commit point). Called once at the start of the device, never while a save may run. Returns whether
    // there was one.
    bool remove_stale_temp() const;

    // Test hook, called inside save() after each step: "temp-written" (temp file written and synced),
    // "renamed" (rename done, directory not yet synced), "done".
    std::function<void(std::string_view step)> on_step;

  private:
    std::string write_atomic(const std::vector<uint8_t>& bytes);  // temp, fsync, rename, fsync dir

    std::filesystem::path dir_;
    std::filesystem::path file_;
};

// Wires 0x1010:01 / 0x2110:01,02,06 (store, signature "save") and 0x1011:01 / 0x2111:01,02,06 (restore,
// signature "load") of `dict` to `store`, for the objects that exist. A wrong signature fails the write
// with Status::CannotStore (SDO abort 0x08000020); a failed file operation with Status::HardwareError.
// On read, 0x1010:01/0x1011:01 show CiA 301's capability bit 0 (= 1), 0x2110/0x2111 the state of the
// last command (bit 0 done, bit 1 error). Both `dict` and `store` must outlive the wiring and stay put.
// `restore_allowed`, if given, is asked before a restore (MAXPOS firmware specification §7.2.21: only with
// every axis in "Power Disable"); a non-Ok answer fails the write with that status and nothing is restored.
// `on_result`, if given, hears every save or restore the store attempted (a right signature), with "" or
// the error text: the device logs both outcomes.
using StoreResult = std::function<void(const Entry& entry, bool save, const std::string& error)>;
void attach_store(Dictionary& dict, ParameterStore& store, std::function<Status()> restore_allowed = {},
                  StoreResult on_result = {});

}  // namespace od
