#pragma once
// ESI (IEC 61131-3 style) names of the CoE data types, shared by the ESI writer and the SII decoder;
// by CoE data type code (ETG.1000.6 Table 64, the values of od::DataType) so the od-free decoder can use it.
#include <cstdint>

namespace esi::detail {

// nullptr for codes without a scalar ESI name (strings get "STRING(n)" etc. from the caller).
inline const char* base_type_name(uint16_t code) {
    switch (code) {
        case 0x0001:  // Boolean
            return "BOOL";
        case 0x0002:  // Integer8
            return "SINT";
        case 0x0003:  // Integer16
            return "INT";
        case 0x0004:  // Integer32
            return "DINT";
        case 0x0005:  // Unsigned8
            return "USINT";
        case 0x0006:  // Unsigned16
            return "UINT";
        case 0x0007:  // Unsigned32
            return "UDINT";
        case 0x0008:  // Real32
            return "REAL";
        case 0x0011:  // Real64
            return "LREAL";
        case 0x0015:  // Integer64
            return "LINT";
        case 0x001B:  // Unsigned64
            return "ULINT";
        case 0x0009:  // VisibleString
            return "STRING";
        case 0x000A:  // OctetString
            return "OCTET_STRING";
        case 0x000B:  // UnicodeString
            return "UNICODE_STRING";
        case 0x0021:  // PdoMapping
            return "PDO_MAPPING";
        case 0x0023:  // Identity
            return "IDENTITY";
        case 0x0029:  // SyncManagerParameter
            return "SYNC_PAR";
        case 0x0010:  // Integer24
            return "INT24";
        case 0x0016:  // Unsigned24
            return "UINT24";
        case 0x0030:  // Bit1 .. Bit8
            return "BIT1";
        case 0x0031:
            return "BIT2";
        case 0x0032:
            return "BIT3";
        case 0x0033:
            return "BIT4";
        case 0x0034:
            return "BIT5";
        case 0x0035:
            return "BIT6";
        case 0x0036:
            return "BIT7";
        case 0x0037:
            return "BIT8";
    }
    return nullptr;
}

}  // namespace esi::detail
