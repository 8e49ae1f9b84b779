#pragma once
// ESI (IEC 61131-3 style) names of the CoE data types, shared by the ESI writer and the SII decoder.
#include <cstdint>

#include "od/types.hpp"

namespace esi::detail {

// nullptr for codes without a scalar ESI name (strings get "STRING(n)" etc. from the caller).
inline const char* base_type_name(uint16_t code) {
    switch (static_cast<od::DataType>(code)) {
        case od::DataType::Boolean:
            return "BOOL";
        case od::DataType::Integer8:
            return "SINT";
        case od::DataType::Integer16:
            return "INT";
        case od::DataType::Integer32:
            return "DINT";
        case od::DataType::Unsigned8:
            return "USINT";
        case od::DataType::Unsigned16:
            return "UINT";
        case od::DataType::Unsigned32:
            return "UDINT";
        case od::DataType::Real32:
            return "REAL";
        case od::DataType::Real64:
            return "LREAL";
        case od::DataType::Integer64:
            return "LINT";
        case od::DataType::Unsigned64:
            return "ULINT";
        case od::DataType::VisibleString:
            return "STRING";
        case od::DataType::OctetString:
            return "OCTET_STRING";
        case od::DataType::UnicodeString:
            return "UNICODE_STRING";
        case od::DataType::PdoMapping:
            return "PDO_MAPPING";
        case od::DataType::Identity:
            return "IDENTITY";
        case od::DataType::SyncManagerParameter:
            return "SYNC_PAR";
    }
    return nullptr;
}

}  // namespace esi::detail
