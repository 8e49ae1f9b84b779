#include "drive/errors.hpp"

namespace drive {
std::span<const ErrorInfo> error_table() {
    return std::span<const ErrorInfo>(kErrorTable);
}

const ErrorInfo* find_error(uint16_t code) {
    return find_error_code(code);
}

}  // namespace drive
