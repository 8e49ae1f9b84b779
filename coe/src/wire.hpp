#pragma once
// Little-endian field access and the CoE header for CoE frames (internal): util/le.hpp and the CoE
// vocabulary (coe/wire/sdo.hpp) under the names the CoE sources use.
#include <cstddef>
#include <cstdint>
#include <span>

#include "coe/wire/sdo.hpp"
#include "util/le.hpp"

namespace coe::wire {

using util::get16;
using util::get32;
using util::put16;
using util::put32;
using util::put64;

using Service = coe::Service;
inline void put_coe_header(uint8_t* p, Service s, uint16_t number = 0) {
    put16(p, coe_header(s, number));
}

}  // namespace coe::wire
