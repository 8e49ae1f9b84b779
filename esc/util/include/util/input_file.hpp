#pragma once
// Reading a file a program was given (configuration, topology, EEPROM image, ESI, firmware image): the
// one check every such read goes through. The path is opened non-blocking (a FIFO without a writer does not
// hang the open), must name a regular file (not a device such as /dev/zero or /dev/urandom, a FIFO or a
// directory) of at most max_bytes, and is then read whole; a file that grows while it is read is refused as
// well. Nothing larger than max_bytes is ever allocated.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace util {

// "PATH: cannot open the topology file: No such file or directory", "PATH: not a regular file (a FIFO)",
// "PATH: larger than 1048576 bytes: not a topology file".
class InputFileError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

// what names the kind of file in the messages ("topology file", "EEPROM image"). Throws InputFileError.
std::string read_input_file(const std::filesystem::path& path, std::size_t max_bytes, std::string_view what);
std::vector<uint8_t> read_input_bytes(const std::filesystem::path& path, std::size_t max_bytes,
                                      std::string_view what);

}  // namespace util
