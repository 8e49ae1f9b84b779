#pragma once
// A device's identity and layout from a configuration file, on top of a product's own description, so one
// binary can be any device of a family (the built-in MAXPOS reads its --config through maxpos::load_config).
//
// Format (the subset of CLI11's INI/TOML config that the `ecat-slave` program reads from the same file):
//   # comment            ; comment
//   [identity]           section headers; keys before any section are read as [identity] keys
//   vendor_id = 0xFB     integers: decimal or 0x hex;  strings: "quoted" (\" \\ escapes), 'literal' or bare
// Sections and keys this module knows (see od/examples/device.conf):
//   [identity]           vendor_id product_code revision serial_number vendor_name device_name
//                        hardware_version software_version order_code group_type
//   [mailbox]            out_start out_size in_start in_size            (standard mailbox, SM0/SM1)
//   [bootstrap_mailbox]  out_start out_size in_start in_size
//   [eeprom]             bytes station_alias pdi_control esc_config pdi_config sync_pulse_length
// Other sections, and unknown keys before the first section, belong to the program and are ignored;
// an unknown key inside a known section, a duplicate key, a bad value or a malformed line is an error.
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "od/device.hpp"

namespace od {

class ConfigError : public std::runtime_error {
  public:
    ConfigError(const std::string& source, int line, const std::string& message)
        : std::runtime_error(text(source, line, message)), line_(line) {}
    int line() const { return line_; }  // 1-based; 0 if the error is not tied to a line

  private:
    // "FILE:LINE: message", or "FILE: message" when no line is to blame. Appended piece by piece: GCC 12 at
    // -O3 misjudges ":" + std::string&& as an overlapping copy (-Werror=restrict, GCC bug 105651).
    static std::string text(const std::string& source, int line, const std::string& message) {
        std::string t = source;
        if (line > 0) {
            t += ':';
            t += std::to_string(line);
        }
        t += ": ";
        t += message;
        return t;
    }
    int line_;
};

// Longest configuration file load_device_config() reads (a real one is a few hundred bytes).
constexpr std::size_t kMaxConfigBytes = 1u << 20;

// Lays out a product's SyncManagers again after the mailbox moved (SM2/SM3 after the mailbox); throws
// std::out_of_range if they do not fit (reported as an error of the file).
using SyncManagerPlacer = std::function<void(DeviceDescription&)>;

// Reads `path` on top of `base`, then calls `place` (if any). Throws ConfigError (file:line: message), also
// for a file longer than kMaxConfigBytes (nothing beyond that is read).
DeviceDescription load_device_config(const std::filesystem::path& path, const DeviceDescription& base,
                                     const SyncManagerPlacer& place = {});

// Same, from text; `source` names it in error messages.
DeviceDescription parse_device_config(std::string_view text, const std::string& source,
                                      const DeviceDescription& base, const SyncManagerPlacer& place = {});

}  // namespace od
