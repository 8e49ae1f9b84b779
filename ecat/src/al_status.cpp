#include "ecat/al_status.hpp"

namespace ecat::al {

std::string_view name(uint16_t code) {
    return status_text(code);
}

}  // namespace ecat::al
