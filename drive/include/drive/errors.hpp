#pragma once
// The drive's error table: code, error-register bits and reaction class (drive/wire/error_codes.hpp).
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "drive/wire/error_codes.hpp"

namespace drive {

// The whole table, in code order.
std::span<const ErrorInfo> error_table();
// nullptr for a code not in the table.
const ErrorInfo* find_error(uint16_t code);

}  // namespace drive
