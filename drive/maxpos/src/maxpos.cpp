// The MAXPOS object dictionary, declared as data: one line per object header or entry, in the order and
// with the values of the MAXPOS firmware specification (maxon), chapter 7 (its § numbers in the comments).
// Where the specification is inconsistent the choice is written down in docs/decisions/od.md.
#include "maxpos/maxpos.hpp"

#include <algorithm>
#include <charconv>
#include <cstring>
#include <stdexcept>
#include <string>
#include <string_view>

#include "drive/wire/diag_texts.hpp"
#include "od/device_config.hpp"
#include "util/strfmt.hpp"
#include "value_names.hpp"

namespace maxpos {

using namespace od;

namespace {

enum Kind : uint8_t { VAR, ARR, REC, SUB };

constexpr uint16_t RO = access::RO;
constexpr uint16_t RW = access::RW;
constexpr uint16_t RWP = access::RW_PreOp;  // "write access only in ESM Pre-Operational"
constexpr uint16_t TX = access::TxPdo;
constexpr uint16_t TRX = access::TxPdo | access::RxPdo;
constexpr uint16_t BK = access::Backup;

constexpr DataType BOOL = DataType::Boolean;
constexpr DataType I8 = DataType::Integer8;
constexpr DataType I16 = DataType::Integer16;
constexpr DataType I32 = DataType::Integer32;
constexpr DataType U8 = DataType::Unsigned8;
constexpr DataType U16 = DataType::Unsigned16;
constexpr DataType U32 = DataType::Unsigned32;
constexpr DataType U64 = DataType::Unsigned64;
constexpr DataType VSTR = DataType::VisibleString;
constexpr DataType OSTR = DataType::OctetString;
constexpr DataType PDOMAP = DataType::PdoMapping;
constexpr DataType IDENT = DataType::Identity;
constexpr DataType SMPAR = DataType::SyncManagerParameter;
constexpr DataType STRUCT = DataType::Unsigned8;  // RECORD without a standard structure type (decisions)

// def/min/max: "" = not given; numbers in C syntax (0x.., -3); "$name" = from the identity; for strings,
// def is the text and max the capacity in bytes. P(name): the entry holds the drive's vendor parameter
// drive::Param::name (drive/objects.hpp), so drive_objects() binds it; its type is checked against the
// parameter's at compile time.
struct Line {
    Kind kind;
    uint16_t index;
    uint8_t sub;
    DataType type;
    uint16_t acc;
    const char* def;
    const char* min;
    const char* max;
    const char* unit;
    const char* name;
    bool binds = false;
    drive::Param param{};
};
#define P(name) true, drive::Param::name

// clang-format off
constexpr Line kTable[] = {
// kind idx  sub type  access     default       min      max          unit     name
{VAR, 0x1000, 0, U32,  RO,        "0x00020192", "",      "",          "",      "Device Type"},                        // 7.2.1
{VAR, 0x1001, 0, U8,   RO|TX,     "0",          "",      "",          "",      "Error Register"},                     // 7.2.2
{VAR, 0x1008, 0, VSTR, RO,        "$device_name", "",    "",          "",      "Manufacturer Device Name"},           // 7.2.3
{VAR, 0x1009, 0, VSTR, RO,        "$hardware_version", "", "",        "",      "Manufacturer Hardware Version"},      // CiA 301 (decisions)
{VAR, 0x100A, 0, VSTR, RO,        "$software_version", "", "",        "",      "Manufacturer Software Version"},      // CiA 301 (decisions)
{ARR, 0x1010, 0, U32,  RO,        "",           "",      "",          "",      "Store Parameters"},                   // CiA 301, EPOS4 Application Notes §7.11
{SUB, 0x1010, 1, U32,  RW,        "0x00000001", "",      "",          "",      "Save all Parameters"},
{ARR, 0x1011, 0, U32,  RO,        "",           "",      "",          "",      "Restore Default Parameters"},         // CiA 301, EPOS4 Application Notes §7.11
{SUB, 0x1011, 1, U32,  RWP,       "0x00000001", "",      "",          "",      "Restore all Default Parameters"},
{REC, 0x1018, 0, IDENT, RO,       "",           "",      "",          "",      "Identity Object"},                    // 7.2.4
{SUB, 0x1018, 1, U32,  RO,        "$vendor_id", "",      "",          "",      "Vendor ID"},
{SUB, 0x1018, 2, U32,  RO,        "$product_code", "",   "",          "",      "Product Code"},
{SUB, 0x1018, 3, U32,  RO,        "$revision",  "",      "",          "",      "Revision Number"},
{SUB, 0x1018, 4, U32,  RO,        "$serial_number", "",  "",          "",      "Serial Number"},
{REC, 0x10F3, 0, STRUCT, RO,      "",           "",      "",          "",      "Diagnosis History"},                  // 7.2.5
{SUB, 0x10F3, 0, U8,   RO,        "15",         "",      "",          "",      "Highest Subindex supported"},
{SUB, 0x10F3, 1, U8,   RO,        "10",         "",      "",          "",      "Maximum Messages"},
{SUB, 0x10F3, 2, U8,   RO,        "0",          "",      "",          "",      "Newest Message"},
{SUB, 0x10F3, 3, U8,   RW,        "0",          "0",     "255",       "",      "Newest Acknowledged Message"},
{SUB, 0x10F3, 4, BOOL, RO|TX,     "0",          "",      "",          "",      "New Messages Available"},
{SUB, 0x10F3, 5, U16,  RW,        "0",          "0",     "15",        "",      "Flags"},
{SUB, 0x10F3, 6, OSTR, RO,        "",           "",      "32",        "",      "Diagnosis Message 1"},
{SUB, 0x10F3, 7, OSTR, RO,        "",           "",      "32",        "",      "Diagnosis Message 2"},
{SUB, 0x10F3, 8, OSTR, RO,        "",           "",      "32",        "",      "Diagnosis Message 3"},
{SUB, 0x10F3, 9, OSTR, RO,        "",           "",      "32",        "",      "Diagnosis Message 4"},
{SUB, 0x10F3, 10, OSTR, RO,       "",           "",      "32",        "",      "Diagnosis Message 5"},
{SUB, 0x10F3, 11, OSTR, RO,       "",           "",      "32",        "",      "Diagnosis Message 6"},
{SUB, 0x10F3, 12, OSTR, RO,       "",           "",      "32",        "",      "Diagnosis Message 7"},
{SUB, 0x10F3, 13, OSTR, RO,       "",           "",      "32",        "",      "Diagnosis Message 8"},
{SUB, 0x10F3, 14, OSTR, RO,       "",           "",      "32",        "",      "Diagnosis Message 9"},
{SUB, 0x10F3, 15, OSTR, RO,       "",           "",      "32",        "",      "Diagnosis Message 10"},
// RxPDO mapping (7.2.6-7.2.9, T7-67...T7-70): counts follow the listed default entries (decisions).
{REC, 0x1600, 0, PDOMAP, RO,      "",           "",      "",          "",      "Receive PDO 1 Mapping"},              // 7.2.6 CSP
{SUB, 0x1600, 0, U8,   RWP|BK,    "8",          "0",     "10",        "",      "Number of mapped Objects in RxPDO 1"},
{SUB, 0x1600, 1, U32,  RWP|BK,    "0x60400010", "",      "",          "",      "1st mapped Object in RxPDO 1"},
{SUB, 0x1600, 2, U32,  RWP|BK,    "0x607A0020", "",      "",          "",      "2nd mapped Object in RxPDO 1"},
{SUB, 0x1600, 3, U32,  RWP|BK,    "0x60B00020", "",      "",          "",      "3rd mapped Object in RxPDO 1"},
{SUB, 0x1600, 4, U32,  RWP|BK,    "0x60B10020", "",      "",          "",      "4th mapped Object in RxPDO 1"},
{SUB, 0x1600, 5, U32,  RWP|BK,    "0x60B20010", "",      "",          "",      "5th mapped Object in RxPDO 1"},
{SUB, 0x1600, 6, U32,  RWP|BK,    "0x60600008", "",      "",          "",      "6th mapped Object in RxPDO 1"},
{SUB, 0x1600, 7, U32,  RWP|BK,    "0x60FE0120", "",      "",          "",      "7th mapped Object in RxPDO 1"},
{SUB, 0x1600, 8, U32,  RWP|BK,    "0x60B80010", "",      "",          "",      "8th mapped Object in RxPDO 1"},
{SUB, 0x1600, 9, U32,  RWP|BK,    "0",          "",      "",          "",      "9th mapped Object in RxPDO 1"},
{SUB, 0x1600, 10, U32, RWP|BK,    "0",          "",      "",          "",      "10th mapped Object in RxPDO 1"},
{REC, 0x1601, 0, PDOMAP, RO,      "",           "",      "",          "",      "Receive PDO 2 Mapping"},              // 7.2.7 CSV
{SUB, 0x1601, 0, U8,   RWP|BK,    "7",          "0",     "10",        "",      "Number of mapped Objects in RxPDO 2"},
{SUB, 0x1601, 1, U32,  RWP|BK,    "0x60400010", "",      "",          "",      "1st mapped Object in RxPDO 2"},
{SUB, 0x1601, 2, U32,  RWP|BK,    "0x60FF0020", "",      "",          "",      "2nd mapped Object in RxPDO 2"},
{SUB, 0x1601, 3, U32,  RWP|BK,    "0x60B10020", "",      "",          "",      "3rd mapped Object in RxPDO 2"},
{SUB, 0x1601, 4, U32,  RWP|BK,    "0x60B20010", "",      "",          "",      "4th mapped Object in RxPDO 2"},
{SUB, 0x1601, 5, U32,  RWP|BK,    "0x60600008", "",      "",          "",      "5th mapped Object in RxPDO 2"},
{SUB, 0x1601, 6, U32,  RWP|BK,    "0x60FE0120", "",      "",          "",      "6th mapped Object in RxPDO 2"},
{SUB, 0x1601, 7, U32,  RWP|BK,    "0x60B80010", "",      "",          "",      "7th mapped Object in RxPDO 2"},
{SUB, 0x1601, 8, U32,  RWP|BK,    "0",          "",      "",          "",      "8th mapped Object in RxPDO 2"},
{SUB, 0x1601, 9, U32,  RWP|BK,    "0",          "",      "",          "",      "9th mapped Object in RxPDO 2"},
{SUB, 0x1601, 10, U32, RWP|BK,    "0",          "",      "",          "",      "10th mapped Object in RxPDO 2"},
{REC, 0x1602, 0, PDOMAP, RO,      "",           "",      "",          "",      "Receive PDO 3 Mapping"},              // 7.2.8 CST
{SUB, 0x1602, 0, U8,   RWP|BK,    "6",          "0",     "10",        "",      "Number of mapped Objects in RxPDO 3"},
{SUB, 0x1602, 1, U32,  RWP|BK,    "0x60400010", "",      "",          "",      "1st mapped Object in RxPDO 3"},
{SUB, 0x1602, 2, U32,  RWP|BK,    "0x60710010", "",      "",          "",      "2nd mapped Object in RxPDO 3"},
{SUB, 0x1602, 3, U32,  RWP|BK,    "0x60B20010", "",      "",          "",      "3rd mapped Object in RxPDO 3"},
{SUB, 0x1602, 4, U32,  RWP|BK,    "0x60600008", "",      "",          "",      "4th mapped Object in RxPDO 3"},
{SUB, 0x1602, 5, U32,  RWP|BK,    "0x60FE0120", "",      "",          "",      "5th mapped Object in RxPDO 3"},
{SUB, 0x1602, 6, U32,  RWP|BK,    "0x60B80010", "",      "",          "",      "6th mapped Object in RxPDO 3"},
{SUB, 0x1602, 7, U32,  RWP|BK,    "0",          "",      "",          "",      "7th mapped Object in RxPDO 3"},
{SUB, 0x1602, 8, U32,  RWP|BK,    "0",          "",      "",          "",      "8th mapped Object in RxPDO 3"},
{SUB, 0x1602, 9, U32,  RWP|BK,    "0",          "",      "",          "",      "9th mapped Object in RxPDO 3"},
{SUB, 0x1602, 10, U32, RWP|BK,    "0",          "",      "",          "",      "10th mapped Object in RxPDO 3"},
{REC, 0x1603, 0, PDOMAP, RO,      "",           "",      "",          "",      "Receive PDO 4 Mapping"},              // 7.2.9 PPM/PVM
{SUB, 0x1603, 0, U8,   RWP|BK,    "8",          "0",     "10",        "",      "Number of mapped Objects in RxPDO 4"},
{SUB, 0x1603, 1, U32,  RWP|BK,    "0x60400010", "",      "",          "",      "1st mapped Object in RxPDO 4"},
{SUB, 0x1603, 2, U32,  RWP|BK,    "0x607A0020", "",      "",          "",      "2nd mapped Object in RxPDO 4"},
{SUB, 0x1603, 3, U32,  RWP|BK,    "0x60FF0020", "",      "",          "",      "3rd mapped Object in RxPDO 4"},
{SUB, 0x1603, 4, U32,  RWP|BK,    "0x60830020", "",      "",          "",      "4th mapped Object in RxPDO 4"},
{SUB, 0x1603, 5, U32,  RWP|BK,    "0x60840020", "",      "",          "",      "5th mapped Object in RxPDO 4"},
{SUB, 0x1603, 6, U32,  RWP|BK,    "0x60810020", "",      "",          "",      "6th mapped Object in RxPDO 4"},
{SUB, 0x1603, 7, U32,  RWP|BK,    "0x60600008", "",      "",          "",      "7th mapped Object in RxPDO 4"},
{SUB, 0x1603, 8, U32,  RWP|BK,    "0x60FE0120", "",      "",          "",      "8th mapped Object in RxPDO 4"},
{SUB, 0x1603, 9, U32,  RWP|BK,    "0",          "",      "",          "",      "9th mapped Object in RxPDO 4"},
{SUB, 0x1603, 10, U32, RWP|BK,    "0",          "",      "",          "",      "10th mapped Object in RxPDO 4"},
// TxPDO mapping (7.2.10-7.2.13, T7-71...T7-74)
{REC, 0x1A00, 0, PDOMAP, RO,      "",           "",      "",          "",      "Transmit PDO 1 Mapping"},             // 7.2.10 CSP
{SUB, 0x1A00, 0, U8,   RWP|BK,    "9",          "0",     "10",        "",      "Number of mapped Objects in TxPDO 1"},
{SUB, 0x1A00, 1, U32,  RWP|BK,    "0x60410010", "",      "",          "",      "1st mapped Object in TxPDO 1"},
{SUB, 0x1A00, 2, U32,  RWP|BK,    "0x60640020", "",      "",          "",      "2nd mapped Object in TxPDO 1"},
{SUB, 0x1A00, 3, U32,  RWP|BK,    "0x606C0020", "",      "",          "",      "3rd mapped Object in TxPDO 1"},
{SUB, 0x1A00, 4, U32,  RWP|BK,    "0x60770010", "",      "",          "",      "4th mapped Object in TxPDO 1"},
{SUB, 0x1A00, 5, U32,  RWP|BK,    "0x60610008", "",      "",          "",      "5th mapped Object in TxPDO 1"},
{SUB, 0x1A00, 6, U32,  RWP|BK,    "0x60FD0020", "",      "",          "",      "6th mapped Object in TxPDO 1"},
{SUB, 0x1A00, 7, U32,  RWP|BK,    "0x60B90010", "",      "",          "",      "7th mapped Object in TxPDO 1"},
{SUB, 0x1A00, 8, U32,  RWP|BK,    "0x60BA0020", "",      "",          "",      "8th mapped Object in TxPDO 1"},
{SUB, 0x1A00, 9, U32,  RWP|BK,    "0x60BB0020", "",      "",          "",      "9th mapped Object in TxPDO 1"},
{SUB, 0x1A00, 10, U32, RWP|BK,    "0",          "",      "",          "",      "10th mapped Object in TxPDO 1"},
{REC, 0x1A01, 0, PDOMAP, RO,      "",           "",      "",          "",      "Transmit PDO 2 Mapping"},             // 7.2.11 CSV
{SUB, 0x1A01, 0, U8,   RWP|BK,    "9",          "0",     "10",        "",      "Number of mapped Objects in TxPDO 2"},
{SUB, 0x1A01, 1, U32,  RWP|BK,    "0x60410010", "",      "",          "",      "1st mapped Object in TxPDO 2"},
{SUB, 0x1A01, 2, U32,  RWP|BK,    "0x60640020", "",      "",          "",      "2nd mapped Object in TxPDO 2"},
{SUB, 0x1A01, 3, U32,  RWP|BK,    "0x606C0020", "",      "",          "",      "3rd mapped Object in TxPDO 2"},
{SUB, 0x1A01, 4, U32,  RWP|BK,    "0x60770010", "",      "",          "",      "4th mapped Object in TxPDO 2"},
{SUB, 0x1A01, 5, U32,  RWP|BK,    "0x60610008", "",      "",          "",      "5th mapped Object in TxPDO 2"},
{SUB, 0x1A01, 6, U32,  RWP|BK,    "0x60FD0020", "",      "",          "",      "6th mapped Object in TxPDO 2"},
{SUB, 0x1A01, 7, U32,  RWP|BK,    "0x60B90010", "",      "",          "",      "7th mapped Object in TxPDO 2"},
{SUB, 0x1A01, 8, U32,  RWP|BK,    "0x60BA0020", "",      "",          "",      "8th mapped Object in TxPDO 2"},
{SUB, 0x1A01, 9, U32,  RWP|BK,    "0x60BB0020", "",      "",          "",      "9th mapped Object in TxPDO 2"},
{SUB, 0x1A01, 10, U32, RWP|BK,    "0",          "",      "",          "",      "10th mapped Object in TxPDO 2"},
{REC, 0x1A02, 0, PDOMAP, RO,      "",           "",      "",          "",      "Transmit PDO 3 Mapping"},             // 7.2.12 CST
{SUB, 0x1A02, 0, U8,   RWP|BK,    "9",          "0",     "10",        "",      "Number of mapped Objects in TxPDO 3"},
{SUB, 0x1A02, 1, U32,  RWP|BK,    "0x60410010", "",      "",          "",      "1st mapped Object in TxPDO 3"},
{SUB, 0x1A02, 2, U32,  RWP|BK,    "0x60640020", "",      "",          "",      "2nd mapped Object in TxPDO 3"},
{SUB, 0x1A02, 3, U32,  RWP|BK,    "0x606C0020", "",      "",          "",      "3rd mapped Object in TxPDO 3"},
{SUB, 0x1A02, 4, U32,  RWP|BK,    "0x60770010", "",      "",          "",      "4th mapped Object in TxPDO 3"},
{SUB, 0x1A02, 5, U32,  RWP|BK,    "0x60610008", "",      "",          "",      "5th mapped Object in TxPDO 3"},
{SUB, 0x1A02, 6, U32,  RWP|BK,    "0x60FD0020", "",      "",          "",      "6th mapped Object in TxPDO 3"},
{SUB, 0x1A02, 7, U32,  RWP|BK,    "0x60B90010", "",      "",          "",      "7th mapped Object in TxPDO 3"},
{SUB, 0x1A02, 8, U32,  RWP|BK,    "0x60BA0020", "",      "",          "",      "8th mapped Object in TxPDO 3"},
{SUB, 0x1A02, 9, U32,  RWP|BK,    "0x60BB0020", "",      "",          "",      "9th mapped Object in TxPDO 3"},
{SUB, 0x1A02, 10, U32, RWP|BK,    "0",          "",      "",          "",      "10th mapped Object in TxPDO 3"},
{REC, 0x1A03, 0, PDOMAP, RO,      "",           "",      "",          "",      "Transmit PDO 4 Mapping"},             // 7.2.13 PPM/PVM
{SUB, 0x1A03, 0, U8,   RWP|BK,    "7",          "0",     "10",        "",      "Number of mapped Objects in TxPDO 4"},
{SUB, 0x1A03, 1, U32,  RWP|BK,    "0x60410010", "",      "",          "",      "1st mapped Object in TxPDO 4"},
{SUB, 0x1A03, 2, U32,  RWP|BK,    "0x60640020", "",      "",          "",      "2nd mapped Object in TxPDO 4"},
{SUB, 0x1A03, 3, U32,  RWP|BK,    "0x606C0020", "",      "",          "",      "3rd mapped Object in TxPDO 4"},
{SUB, 0x1A03, 4, U32,  RWP|BK,    "0x60780010", "",      "",          "",      "4th mapped Object in TxPDO 4"},
{SUB, 0x1A03, 5, U32,  RWP|BK,    "0x60F40020", "",      "",          "",      "5th mapped Object in TxPDO 4"},
{SUB, 0x1A03, 6, U32,  RWP|BK,    "0x60610008", "",      "",          "",      "6th mapped Object in TxPDO 4"},
{SUB, 0x1A03, 7, U32,  RWP|BK,    "0x60FD0020", "",      "",          "",      "7th mapped Object in TxPDO 4"},
{SUB, 0x1A03, 8, U32,  RWP|BK,    "0",          "",      "",          "",      "8th mapped Object in TxPDO 4"},
{SUB, 0x1A03, 9, U32,  RWP|BK,    "0",          "",      "",          "",      "9th mapped Object in TxPDO 4"},
{SUB, 0x1A03, 10, U32, RWP|BK,    "0",          "",      "",          "",      "10th mapped Object in TxPDO 4"},
// Sync managers (7.2.14-7.2.18)
{ARR, 0x1C00, 0, U8,   RO,        "",           "",      "",          "",      "Sync Manager Communication Type"},    // 7.2.14
{SUB, 0x1C00, 0, U8,   RO,        "4",          "",      "",          "",      "Number of used Sync Manager Channels"},
{SUB, 0x1C00, 1, U8,   RO,        "1",          "",      "",          "",      "Communication Type Sync Channel 0"},
{SUB, 0x1C00, 2, U8,   RO,        "2",          "",      "",          "",      "Communication Type Sync Channel 1"},
{SUB, 0x1C00, 3, U8,   RO,        "3",          "",      "",          "",      "Communication Type Sync Channel 2"},
{SUB, 0x1C00, 4, U8,   RO,        "4",          "",      "",          "",      "Communication Type Sync Channel 3"},
{ARR, 0x1C12, 0, U16,  RO,        "",           "",      "",          "",      "Sync Manager 2 PDO Assignment"},      // 7.2.15
{SUB, 0x1C12, 0, U8,   RWP|BK,    "1",          "0",     "4",         "",      "Number of assigned RxPDOs"},
{SUB, 0x1C12, 1, U16,  RWP|BK,    "0x1600",     "0x1600", "0x1603",   "",      "1st assigned RxPDO"},
{SUB, 0x1C12, 2, U16,  RWP|BK,    "0x1601",     "0x1600", "0x1603",   "",      "2nd assigned RxPDO"},
{SUB, 0x1C12, 3, U16,  RWP|BK,    "0x1602",     "0x1600", "0x1603",   "",      "3rd assigned RxPDO"},
{SUB, 0x1C12, 4, U16,  RWP|BK,    "0x1603",     "0x1600", "0x1603",   "",      "4th assigned RxPDO"},
{ARR, 0x1C13, 0, U16,  RO,        "",           "",      "",          "",      "Sync Manager 3 PDO Assignment"},      // 7.2.16
{SUB, 0x1C13, 0, U8,   RWP|BK,    "1",          "0",     "4",         "",      "Number of assigned TxPDOs"},
{SUB, 0x1C13, 1, U16,  RWP|BK,    "0x1A00",     "0x1A00", "0x1A03",   "",      "1st assigned TxPDO"},
{SUB, 0x1C13, 2, U16,  RWP|BK,    "0x1A01",     "0x1A00", "0x1A03",   "",      "2nd assigned TxPDO"},
{SUB, 0x1C13, 3, U16,  RWP|BK,    "0x1A02",     "0x1A00", "0x1A03",   "",      "3rd assigned TxPDO"},
{SUB, 0x1C13, 4, U16,  RWP|BK,    "0x1A03",     "0x1A00", "0x1A03",   "",      "4th assigned TxPDO"},
{REC, 0x1C32, 0, SMPAR, RO,       "",           "",      "",          "",      "Sync Manager Output Parameter"},      // 7.2.17
{SUB, 0x1C32, 0, U8,   RO,        "5",          "",      "",          "",      "Highest Subindex supported"},
{SUB, 0x1C32, 1, U16,  RWP,       "2",          "1",     "2",         "",      "Sync Mode"},
{SUB, 0x1C32, 2, U32,  RWP,       "1000000",    "",      "",          "ns",    "Cycle Time"},
{SUB, 0x1C32, 3, U32,  RO,        "0",          "",      "",          "ns",    "Shift Time"},
{SUB, 0x1C32, 4, U16,  RO,        "0x0006",     "",      "",          "",      "Sync Modes Supported"},
{SUB, 0x1C32, 5, U32,  RO,        "100000",     "",      "",          "ns",    "Min Cycle Time"},
{REC, 0x1C33, 0, SMPAR, RO,       "",           "",      "",          "",      "Sync Manager Input Parameter"},       // 7.2.18
{SUB, 0x1C33, 0, U8,   RO,        "5",          "",      "",          "",      "Highest Subindex supported"},
{SUB, 0x1C33, 1, U16,  RWP,       "2",          "1",     "34",        "",      "Sync Mode"},
{SUB, 0x1C33, 2, U32,  RWP,       "1000000",    "",      "",          "ns",    "Cycle Time"},
{SUB, 0x1C33, 3, U32,  RO,        "50000",      "",      "",          "ns",    "Shift Time"},
{SUB, 0x1C33, 4, U16,  RO,        "0x0006",     "",      "",          "",      "Sync Modes Supported"},
{SUB, 0x1C33, 5, U32,  RO,        "100000",     "",      "",          "ns",    "Min Cycle Time"},
// Manufacturer objects (7.2.19-7.2.43)
{VAR, 0x2100, 0, U64,  RO,        "$serial_number", "",  "",          "",      "Serial Number Complete"},             // 7.2.19
{ARR, 0x2110, 0, U32,  RO,        "",           "",      "",          "",      "Store Parameters"},                   // 7.2.20
{SUB, 0x2110, 1, U32,  RW,        "0",          "",      "",          "",      "Store All Parameters"},
{SUB, 0x2110, 2, U32,  RW,        "0",          "",      "",          "",      "Store Communication Parameters"},
{SUB, 0x2110, 6, U32,  RW,        "0",          "",      "",          "",      "Store Axis Parameters"},
{ARR, 0x2111, 0, U32,  RO,        "",           "",      "",          "",      "Restore Default Parameters"},         // 7.2.21
{SUB, 0x2111, 1, U32,  RWP,       "0",          "",      "",          "",      "Restore All Default Parameters"},
{SUB, 0x2111, 2, U32,  RWP,       "0",          "",      "",          "",      "Restore Communication Default Parameters"},
{SUB, 0x2111, 6, U32,  RWP,       "0",          "",      "",          "",      "Restore Axis Default Parameters"},
{ARR, 0x3000, 0, U32,  RO,        "",           "",      "",          "",      "Axis Configuration"},                 // 7.2.22
{SUB, 0x3000, 1, U32,  RW|BK,     "0x00100001", "",      "",          "",      "Sensors Configuration"},
{SUB, 0x3000, 2, U32,  RW|BK,     "0x00000011", "",      "",          "",      "Control Structure"},
{SUB, 0x3000, 3, U32,  RW|BK,     "0x00000031", "",      "",          "",      "Commutation Sensors"},
{SUB, 0x3000, 4, U32,  RW|BK,     "0",          "",      "",          "",      "Axis Configuration Miscellaneous", P(AxisConfigurationMisc)},
{SUB, 0x3000, 5, U32,  RO,        "2000",       "",      "",          "inc",   "Main Sensor Resolution", P(MainSensorResolution)},
{REC, 0x3001, 0, STRUCT, RO,      "",           "",      "",          "",      "Motor Data"},                         // 7.2.23
{SUB, 0x3001, 1, U16,  RW|BK,     "5000",       "0",     "5000",      "mA",    "Nominal Current", P(MotorNominalCurrent)},
{SUB, 0x3001, 2, U16,  RW|BK,     "15000",      "0",     "15000",     "mA",    "Output Current Limit", P(MotorOutputCurrentLimit)},
{SUB, 0x3001, 3, U8,   RW|BK,     "1",          "1",     "31",        "",      "Number of Pole Pairs", P(MotorPolePairs)},
{SUB, 0x3001, 4, U16,  RW|BK,     "40",         "1",     "10000",     "0.1 s", "Thermal Time Constant Winding", P(MotorThermalTimeConstant)},
{SUB, 0x3001, 5, U32,  RW|BK,     "0",          "0",     "10000000",  "uNm/A", "Torque Constant", P(MotorTorqueConstant)},
{REC, 0x3010, 0, STRUCT, RO,      "",           "",      "",          "",      "Digital Incremental Encoder 1"},      // 7.2.24
{SUB, 0x3010, 1, U32,  RW|BK,     "500",        "16",    "2500000",   "pulse/rev", "Digital Incremental Encoder 1 Number of Pulses", P(EncoderPulses)},
{SUB, 0x3010, 2, U16,  RW|BK,     "1",          "",      "",          "",      "Digital Incremental Encoder 1 Type", P(EncoderType)},
{SUB, 0x3010, 4, I32,  RO|TX,     "0",          "",      "",          "inc",   "Digital Incremental Encoder 1 Index Position", P(EncoderIndexPosition)},
{REC, 0x3011, 0, STRUCT, RO,      "",           "",      "",          "",      "Analog Incremental Encoder"},         // 7.2.25
{SUB, 0x3011, 1, U16,  RW|BK,     "0x0001",     "",      "",          "",      "Analog Incremental Encoder Type"},
{SUB, 0x3011, 2, U32,  RW|BK,     "0x00080004", "",      "",          "",      "Analog Incremental Encoder Resolution"},
{SUB, 0x3011, 3, I32,  RO|TX,     "0",          "",      "",          "inc",   "Analog Incremental Encoder Index Position"},
{REC, 0x3012, 0, STRUCT, RO,      "",           "",      "",          "",      "SSI Absolute Encoder"},               // 7.2.26
{SUB, 0x3012, 1, U16,  RW|BK,     "500",        "80",    "3000",      "kbit/s", "SSI Data Rate"},
{SUB, 0x3012, 2, U32,  RW|BK,     "0x000C0D00", "",      "",          "",      "SSI Number of Data Bits"},
{SUB, 0x3012, 3, U16,  RW|BK,     "0x0000",     "",      "",          "",      "SSI Encoding Type"},
{SUB, 0x3012, 4, U16,  RW|BK,     "0",          "0",     "500",       "0.1 us", "SSI Transmit Wait Time"},
{SUB, 0x3012, 5, U16,  RW|BK,     "300",        "0",     "500",       "0.1 us", "SSI Timeout Time"},
{SUB, 0x3012, 6, U16,  RO|TX,     "0",          "",      "",          "",      "SSI Special Bits"},
{SUB, 0x3012, 7, U32,  RO,        "0",          "",      "",          "Hz",    "SSI Refresh Rate"},
{SUB, 0x3012, 8, U16,  RW|BK,     "200",        "0",     "10000",     "ms",    "SSI Power-up Time"},
{REC, 0x3014, 0, STRUCT, RO,      "",           "",      "",          "",      "BiSS Absolute Encoder"},              // 7.2.27
{SUB, 0x3014, 1, U8,   RW,        "0",          "",      "",          "",      "BiSS Encoder Controlword"},
{SUB, 0x3014, 2, U16,  RO,        "0",          "",      "",          "",      "BiSS Encoder Statusword"},
{SUB, 0x3014, 3, U16,  RW|BK,     "4687",       "2000",  "10000",     "kbit/s", "BiSS Encoder Data Rate"},
{SUB, 0x3014, 4, U16,  RW|BK,     "500",        "0",     "4000",      "0.01 us", "BiSS Encoder Timeout Time"},
{SUB, 0x3014, 5, U16,  RW|BK,     "0",          "0",     "4000",      "0.01 us", "BiSS Encoder Busy Time"},
{SUB, 0x3014, 6, U32,  RW|BK,     "0x0400000C", "",      "",          "",      "BiSS Encoder Data Bits"},
{SUB, 0x3014, 7, U32,  RW|BK,     "12",         "",      "",          "",      "BiSS Encoder Position Bits"},
{SUB, 0x3014, 8, U16,  RW|BK,     "0",          "",      "",          "",      "BiSS Encoder Type"},
{SUB, 0x3014, 9, U32,  RW|BK,     "0x00430010", "",      "",          "",      "BiSS Encoder Protocol"},
{SUB, 0x3014, 10, U16, RO,        "0",          "",      "",          "Hz",    "BiSS Encoder Refresh Rate"},
{SUB, 0x3014, 11, U16, RO,        "0",          "",      "",          "",      "BiSS Encoder Profile ID"},
{SUB, 0x3014, 12, U32, RO,        "0",          "",      "",          "",      "BiSS Encoder Serial Number"},
{SUB, 0x3014, 13, U64, RO,        "0",          "",      "",          "",      "BiSS Encoder Device ID"},
{SUB, 0x3014, 14, U16, RO,        "0",          "",      "",          "",      "BiSS Encoder Manufacturer ID"},
{REC, 0x301A, 0, STRUCT, RO,      "",           "",      "",          "",      "Digital Hall Sensor"},                // 7.2.28
{SUB, 0x301A, 1, U16,  RW|BK,     "0",          "",      "",          "",      "Digital Hall Sensor Type"},
{SUB, 0x301A, 2, U16,  RO,        "0",          "",      "",          "",      "Digital Hall Sensor Pattern"},
{REC, 0x3020, 0, STRUCT, RO,      "",           "",      "",          "",      "Digital Incremental Encoder 2"},      // 7.2.29
{SUB, 0x3020, 1, U32,  RW|BK,     "500",        "16",    "2500000",   "pulse/rev", "Digital Incremental Encoder 2 Number of Pulses"},
{SUB, 0x3020, 2, U16,  RW|BK,     "0x0001",     "",      "",          "",      "Digital Incremental Encoder 2 Type"},
{SUB, 0x3020, 4, I32,  RO|TX,     "0",          "",      "",          "inc",   "Digital Incremental Encoder 2 Index Position"},
{ARR, 0x30A0, 0, U32,  RO,        "",           "",      "",          "",      "Current Control Parameter Set"},      // 7.2.30
{SUB, 0x30A0, 1, U32,  RW|TRX|BK, "32768",      "",      "",          "2^-16 V/A", "Current Regulator P Gain", P(CurrentPGain)},
{SUB, 0x30A0, 2, U32,  RW|TRX|BK, "4096",       "",      "",          "2^-16 V/(A*ms)", "Current Regulator I Gain", P(CurrentIGain)},
{SUB, 0x30A0, 3, U32,  RW|TRX|BK, "0",          "",      "",          "2^-16 V/A", "Current Regulator FF Gain", P(CurrentFfGain)},
{ARR, 0x30A1, 0, U32,  RO,        "",           "",      "",          "",      "Position Control Parameter Set"},     // 7.2.31
{SUB, 0x30A1, 1, U32,  RW|TRX|BK, "4000",       "10",    "1000000",   "mHz",   "Position Regulator Bandwidth", P(PositionBandwidth)},
{SUB, 0x30A1, 2, U32,  RW|TRX|BK, "1000",       "0",     "10000",     "0.1 %", "Position Regulator Damping", P(PositionDamping)},
{SUB, 0x30A1, 3, U32,  RW|TRX|BK, "1000000",    "100",   "3600000000", "us",   "Position Regulator Reset Time", P(PositionResetTime)},
{SUB, 0x30A1, 4, U32,  RW|TRX|BK, "100000",     "10",    "1000000000", "mg*cm^2", "Inertia", P(Inertia)},
{SUB, 0x30A1, 5, U32,  RW|TRX|BK, "0",          "0",     "1000000000", "nNm/rpm", "Friction", P(Friction)},
{VAR, 0x30B0, 0, I32,  RW|TRX|BK, "0",          "",      "",          "inc",   "Home Position", P(HomePosition)},                      // 7.2.32
{VAR, 0x30B1, 0, I32,  RW|BK,     "0",          "",      "",          "inc",   "Home Offset Move Distance", P(HomeOffsetMoveDistance)},          // 7.2.33
{VAR, 0x30B2, 0, U16,  RW|BK,     "500",        "",      "",          "mA",    "Current Threshold for Homing Mode", P(HomingCurrentThreshold)},  // 7.2.34
{VAR, 0x30D0, 0, I16,  RO|TX,     "0",          "",      "",          "mA",    "Current Demand Value", P(CurrentDemandValue)},               // 7.2.35
{VAR, 0x30D1, 0, I16,  RO|TX,     "0",          "",      "",          "mA",    "Current Actual Value Averaged", P(CurrentActualValueAveraged)},      // 7.2.36
{VAR, 0x30D5, 0, I32,  RO|TX,     "0",          "",      "",          "rpm",   "Velocity Actual Value Averaged", P(VelocityActualValueAveraged)},     // 7.2.37
{REC, 0x30E0, 0, STRUCT, RO,      "",           "",      "",          "",      "Standstill Window Configuration"},    // 7.2.38
{SUB, 0x30E0, 1, U32,  RW|BK,     "30",         "",      "",          "rpm",   "Standstill Window", P(StandstillWindow)},
{SUB, 0x30E0, 2, U16,  RW|BK,     "50",         "",      "",          "ms",    "Standstill Window Time", P(StandstillWindowTime)},
{SUB, 0x30E0, 3, U16,  RW|BK,     "1000",       "",      "",          "ms",    "Standstill Window Timeout", P(StandstillWindowTimeout)},
{ARR, 0x3141, 0, U16,  RO,        "",           "",      "",          "",      "Digital Input Properties"},           // 7.2.39
{SUB, 0x3141, 1, U16,  RO|TX,     "0",          "",      "",          "",      "Digital Input Properties Logic State", P(DigitalInputLogicState)},
{SUB, 0x3141, 2, U16,  RW|BK,     "0",          "0",     "0x003F",    "",      "Digital Input Properties Polarity", P(DigitalInputPolarity)},
{ARR, 0x3142, 0, U8,   RO,        "",           "",      "",          "",      "Configuration of Digital Inputs"},    // 7.2.40
{SUB, 0x3142, 1, U8,   RW|BK,     "0",          "",      "",          "",      "Configuration of Digital Input 1", P(DigitalInput1Configuration)},
{SUB, 0x3142, 2, U8,   RW|BK,     "1",          "",      "",          "",      "Configuration of Digital Input 2", P(DigitalInput2Configuration)},
{SUB, 0x3142, 3, U8,   RW|BK,     "2",          "",      "",          "",      "Configuration of Digital Input 3", P(DigitalInput3Configuration)},
{SUB, 0x3142, 4, U8,   RW|BK,     "19",         "",      "",          "",      "Configuration of Digital Input 4", P(DigitalInput4Configuration)},
{SUB, 0x3142, 5, U8,   RW|BK,     "20",         "",      "",          "",      "Configuration of Digital Input 5", P(DigitalInput5Configuration)},
{SUB, 0x3142, 6, U8,   RW|BK,     "21",         "",      "",          "",      "Configuration of Digital Input 6", P(DigitalInput6Configuration)},
{ARR, 0x3150, 0, U16,  RO,        "",           "",      "",          "",      "Digital Output Properties"},          // 7.2.41
{SUB, 0x3150, 1, U16,  RO|TX,     "0",          "",      "",          "",      "Digital Output Properties Logic State"},
{SUB, 0x3150, 2, U16,  RW|BK,     "0x0000",     "0",     "0x0007",    "",      "Digital Output Properties Polarity"},
{ARR, 0x3151, 0, U8,   RO,        "",           "",      "",          "",      "Configuration of Digital Outputs"},   // 7.2.42
{SUB, 0x3151, 1, U8,   RW|BK,     "16",         "",      "",          "",      "Configuration of Digital Output 1"},
{SUB, 0x3151, 2, U8,   RW|BK,     "17",         "",      "",          "",      "Configuration of Digital Output 2"},
{SUB, 0x3151, 3, U8,   RW|BK,     "18",         "",      "",          "",      "Configuration of Digital Output 3"},
{ARR, 0x3158, 0, U16,  RO,        "",           "",      "",          "",      "Holding Brake Configuration"},        // 7.2.43
{SUB, 0x3158, 1, U16,  RW|BK,     "10",         "",      "",          "ms",    "Holding Brake Rise Time"},
{SUB, 0x3158, 2, U16,  RW|BK,     "10",         "",      "",          "ms",    "Holding Brake Fall Time"},
// CiA 402 (7.2.44-7.2.101)
{VAR, 0x6007, 0, I16,  RW|BK,     "3",          "1",     "3",         "",      "Abort Connection Option Code"},       // 7.2.44
{VAR, 0x603F, 0, U16,  RO|TX,     "0",          "",      "",          "",      "Error Code"},                         // 7.2.45
{VAR, 0x6040, 0, U16,  RW|TRX,    "0",          "",      "",          "",      "Controlword"},                        // 7.2.46
{VAR, 0x6041, 0, U16,  RO|TX,     "0",          "",      "",          "",      "Statusword"},                         // 7.2.47
{VAR, 0x605A, 0, I16,  RW|BK,     "6",          "6",     "6",         "",      "Quick Stop Option Code"},             // 7.2.48
{VAR, 0x605B, 0, I16,  RW|BK,     "0",          "0",     "1",         "",      "Shutdown Option Code"},               // 7.2.49
{VAR, 0x605C, 0, I16,  RW|BK,     "1",          "0",     "1",         "",      "Disable Operation Option Code"},      // 7.2.50
{VAR, 0x605D, 0, I16,  RW|BK,     "2",          "2",     "2",         "",      "Halt Option Code"},                   // 7.2.51
{VAR, 0x605E, 0, I16,  RW|BK,     "2",          "-1",    "2",         "",      "Fault Reaction Option Code"},         // 7.2.52
{VAR, 0x6060, 0, I8,   RW|TRX,    "8",          "",      "",          "",      "Modes of Operation"},                 // 7.2.53
{VAR, 0x6061, 0, I8,   RO|TX,     "1",          "",      "",          "",      "Modes of Operation Display"},         // 7.2.54
{VAR, 0x6062, 0, I32,  RO|TX,     "0",          "",      "",          "inc",   "Position Demand Value"},              // 7.2.55
{VAR, 0x6064, 0, I32,  RO|TX,     "0",          "",      "",          "inc",   "Position Actual Value"},              // 7.2.56
{VAR, 0x6065, 0, U32,  RW|TRX|BK, "2000",       "",      "",          "inc",   "Following Error Window"},             // 7.2.57
{VAR, 0x6066, 0, U16,  RW|TRX|BK, "0",          "0",     "0",         "ms",    "Following Error Timeout"},            // 7.2.58
{VAR, 0x606B, 0, I32,  RO|TX,     "0",          "",      "",          "rpm",   "Velocity Demand Value"},              // 7.2.59
{VAR, 0x606C, 0, I32,  RO|TX,     "0",          "",      "",          "rpm",   "Velocity Actual Value"},              // 7.2.60
{VAR, 0x6071, 0, I16,  RW|TRX,    "0",          "",      "",          "0.1 %", "Target Torque"},                      // 7.2.61
{VAR, 0x6076, 0, U32,  RO|TX,     "0",          "",      "",          "uNm",   "Motor Rated Torque"},                 // 7.2.62
{VAR, 0x6077, 0, I16,  RO|TX,     "0",          "",      "",          "0.1 %", "Torque Actual Value"},                // 7.2.63
{VAR, 0x6078, 0, I16,  RO|TX,     "0",          "",      "",          "mA",    "Current Actual Value"},               // 7.2.64
{VAR, 0x607A, 0, I32,  RW|TRX,    "0",          "",      "",          "inc",   "Target Position"},                    // 7.2.65
{ARR, 0x607B, 0, I32,  RO,        "",           "",      "",          "",      "Position Range Limit"},               // 7.2.66
{SUB, 0x607B, 1, I32,  RW|TRX|BK, "-2147483648", "",     "",          "inc",   "Min Position Range Limit"},
{SUB, 0x607B, 2, I32,  RW|TRX|BK, "2147483647", "",      "",          "inc",   "Max Position Range Limit"},
{ARR, 0x607D, 0, I32,  RO,        "",           "",      "",          "",      "Software Position Limit"},            // 7.2.67
{SUB, 0x607D, 1, I32,  RW|TRX|BK, "-2147483648", "",     "",          "inc",   "Min Position Limit"},
{SUB, 0x607D, 2, I32,  RW|TRX|BK, "2147483647", "",      "",          "inc",   "Max Position Limit"},
{VAR, 0x607F, 0, U32,  RW|TRX|BK, "200000",     "1",     "",          "rpm",   "Max Profile Velocity"},               // 7.2.68
{VAR, 0x6080, 0, U32,  RW|BK,     "200000",     "1",     "200000",    "rpm",   "Max Motor Speed"},                    // 7.2.69
{VAR, 0x6081, 0, U32,  RW|TRX|BK, "1000",       "1",     "",          "rpm",   "Profile Velocity"},                   // 7.2.70
{VAR, 0x6083, 0, U32,  RW|TRX|BK, "10000",      "1",     "",          "rpm/s", "Profile Acceleration"},               // 7.2.71
{VAR, 0x6084, 0, U32,  RW|TRX|BK, "10000",      "1",     "",          "rpm/s", "Profile Deceleration"},               // 7.2.72
{VAR, 0x6085, 0, U32,  RW|TRX|BK, "15000",      "1",     "",          "rpm/s", "Quick Stop Deceleration"},            // 7.2.73
{VAR, 0x6086, 0, I16,  RW|TRX|BK, "0",          "0",     "0",         "",      "Motion Profile Type"},                // 7.2.74
{VAR, 0x6098, 0, I8,   RW|TRX|BK, "37",         "",      "",          "",      "Homing Method"},                      // 7.2.75
{ARR, 0x6099, 0, U32,  RO,        "",           "",      "",          "",      "Homing Speeds"},                      // 7.2.76
{SUB, 0x6099, 1, U32,  RW|TRX|BK, "100",        "1",     "",          "rpm",   "Speed for Switch Search"},
{SUB, 0x6099, 2, U32,  RW|TRX|BK, "10",         "1",     "",          "rpm",   "Speed for Zero Search"},
{VAR, 0x609A, 0, U32,  RW|TRX|BK, "1000",       "1",     "",          "rpm/s", "Homing Acceleration"},                // 7.2.77
{VAR, 0x60A8, 0, U32,  RW|TRX|BK, "0x00B50000", "0x00B50000", "0x00B50000", "", "SI Unit Position"},                  // 7.2.78
{VAR, 0x60A9, 0, U32,  RW|BK,     "0x00B44700", "0x00B44700", "0x00B44700", "", "SI Unit Velocity"},                  // 7.2.79
{VAR, 0x60AA, 0, U32,  RW|BK,     "0x00C00300", "0x00C00300", "0x00C00300", "", "SI Unit Acceleration"},              // 7.2.80
{VAR, 0x60B0, 0, I32,  RW|TRX,    "0",          "",      "",          "inc",   "Position Offset"},                    // 7.2.81
{VAR, 0x60B1, 0, I32,  RW|TRX,    "0",          "-200000", "200000",  "rpm",   "Velocity Offset"},                    // 7.2.82
{VAR, 0x60B2, 0, I16,  RW|TRX,    "0",          "",      "",          "0.1 %", "Torque Offset"},                      // 7.2.83
{VAR, 0x60B8, 0, U16,  RW|TRX|BK, "0",          "",      "",          "",      "Touch Probe Function"},               // 7.2.84
{VAR, 0x60B9, 0, U16,  RO|TX,     "0",          "",      "",          "",      "Touch Probe Status"},                 // 7.2.85
{VAR, 0x60BA, 0, I32,  RO|TX,     "0",          "",      "",          "inc",   "Touch Probe Position 1 Positive Value"}, // 7.2.86
{VAR, 0x60BB, 0, I32,  RO|TX,     "0",          "",      "",          "inc",   "Touch Probe Position 1 Negative Value"}, // 7.2.87
{REC, 0x60C2, 0, STRUCT, RO,      "",           "",      "",          "",      "Interpolation Time Period"},          // 7.2.88
{SUB, 0x60C2, 1, U8,   RW|TRX|BK, "1",          "1",     "1",         "",      "Interpolation Time Period Value"},
{SUB, 0x60C2, 2, I8,   RW|TRX|BK, "-3",         "-3",    "-3",        "",      "Interpolation Time Index"},
{VAR, 0x60C5, 0, U32,  RW|BK,     "0xFFFFFFFF", "1",     "4294967295", "rpm/s", "Max Acceleration"},                  // 7.2.89
{ARR, 0x60D0, 0, I16,  RO,        "",           "",      "",          "",      "Touch Probe Source"},                 // 7.2.90
{SUB, 0x60D0, 1, I16,  RO,        "-1",         "",      "",          "",      "Touch Probe 1 Source"},
{VAR, 0x60D5, 0, U16,  RO|TX,     "0",          "",      "",          "",      "Touch Probe 1 Positive Edge Counter"}, // 7.2.91
{VAR, 0x60D6, 0, U16,  RO|TX,     "0",          "",      "",          "",      "Touch Probe 1 Negative Edge Counter"}, // 7.2.92
{ARR, 0x60E3, 0, I16,  RO,        "",           "",      "",          "",      "Supported Homing Methods"},           // 7.2.93
{SUB, 0x60E3, 1, I16,  RO,        "1",          "",      "",          "",      "1st Supported Homing Method"},
{SUB, 0x60E3, 2, I16,  RO,        "2",          "",      "",          "",      "2nd Supported Homing Method"},
{SUB, 0x60E3, 3, I16,  RO,        "7",          "",      "",          "",      "3rd Supported Homing Method"},
{SUB, 0x60E3, 4, I16,  RO,        "11",         "",      "",          "",      "4th Supported Homing Method"},
{SUB, 0x60E3, 5, I16,  RO,        "17",         "",      "",          "",      "5th Supported Homing Method"},
{SUB, 0x60E3, 6, I16,  RO,        "18",         "",      "",          "",      "6th Supported Homing Method"},
{SUB, 0x60E3, 7, I16,  RO,        "23",         "",      "",          "",      "7th Supported Homing Method"},
{SUB, 0x60E3, 8, I16,  RO,        "27",         "",      "",          "",      "8th Supported Homing Method"},
{SUB, 0x60E3, 9, I16,  RO,        "33",         "",      "",          "",      "9th Supported Homing Method"},
{SUB, 0x60E3, 10, I16, RO,        "34",         "",      "",          "",      "10th Supported Homing Method"},
{SUB, 0x60E3, 11, I16, RO,        "37",         "",      "",          "",      "11th Supported Homing Method"},
{SUB, 0x60E3, 12, I16, RO,        "-1",         "",      "",          "",      "12th Supported Homing Method"},
{SUB, 0x60E3, 13, I16, RO,        "-2",         "",      "",          "",      "13th Supported Homing Method"},
{SUB, 0x60E3, 14, I16, RO,        "-3",         "",      "",          "",      "14th Supported Homing Method"},
{SUB, 0x60E3, 15, I16, RO,        "-4",         "",      "",          "",      "15th Supported Homing Method"},
{ARR, 0x60E4, 0, I32,  RO,        "",           "",      "",          "",      "Additional Position Actual Values"},   // 7.2.94
{SUB, 0x60E4, 1, I32,  RO|TX,     "0",          "",      "",          "inc",   "Position Actual Value Sensor 1", P(PositionActualValueSensor1)},
{SUB, 0x60E4, 2, I32,  RO|TX,     "0",          "",      "",          "inc",   "Position Actual Value Sensor 2"},
{SUB, 0x60E4, 3, I32,  RO|TX,     "0",          "",      "",          "inc",   "Position Actual Value Sensor 3"},
{ARR, 0x60E5, 0, I32,  RO,        "",           "",      "",          "",      "Additional Velocity Actual Values"},   // 7.2.95
{SUB, 0x60E5, 1, I32,  RO|TX,     "0",          "",      "",          "rpm",   "Velocity Actual Value Sensor 1", P(VelocityActualValueSensor1)},
{SUB, 0x60E5, 2, I32,  RO|TX,     "0",          "",      "",          "rpm",   "Velocity Actual Value Sensor 2"},
{SUB, 0x60E5, 3, I32,  RO|TX,     "0",          "",      "",          "rpm",   "Velocity Actual Value Sensor 3"},
{SUB, 0x60E5, 9, I32,  RO|TX,     "0",          "",      "",          "rpm",   "Velocity Actual Value Averaged Sensor 1", P(VelocityActualAveragedSensor1)},
{SUB, 0x60E5, 10, I32, RO|TX,     "0",          "",      "",          "rpm",   "Velocity Actual Value Averaged Sensor 2"},
{SUB, 0x60E5, 11, I32, RO|TX,     "0",          "",      "",          "rpm",   "Velocity Actual Value Averaged Sensor 3"},
{VAR, 0x60F4, 0, I32,  RO|TX,     "0",          "",      "",          "inc",   "Following Error Actual Value"},       // 7.2.96
{VAR, 0x60FD, 0, U32,  RO|TX,     "0",          "",      "",          "",      "Digital Inputs"},                     // 7.2.97
{ARR, 0x60FE, 0, U32,  RO,        "",           "",      "",          "",      "Digital Outputs"},                    // 7.2.98
{SUB, 0x60FE, 1, U32,  RW|TRX,    "0",          "",      "",          "",      "Physical Outputs"},
{VAR, 0x60FF, 0, I32,  RW|TRX,    "0",          "-200000", "200000",  "rpm",   "Target Velocity"},                    // 7.2.99
{VAR, 0x6402, 0, U16,  RW|BK,     "10",         "1",     "10",        "",      "Motor Type"},                         // 7.2.100
{VAR, 0x6502, 0, U32,  RO,        "0x000003A5", "",      "",          "",      "Supported Drive Modes"},              // 7.2.101
// Modular device profile (7.2.102-7.2.104)
{REC, 0xF000, 0, STRUCT, RO,      "",           "",      "",          "",      "Modular Device Profile"},             // 7.2.102
{SUB, 0xF000, 1, U16,  RO,        "0x0010",     "",      "",          "",      "Index Distance"},
{SUB, 0xF000, 2, U16,  RO,        "1",          "",      "",          "",      "Maximum Number of Modules"},
{ARR, 0xF010, 0, U32,  RO,        "",           "",      "",          "",      "Module Profile List"},                // 7.2.103
{SUB, 0xF010, 1, U32,  RO,        "0x001002E6", "",      "",          "",      "Module 1"},
{SUB, 0xF010, 2, U32,  RO,        "0x002002E6", "",      "",          "",      "Module 2"},
{SUB, 0xF010, 3, U32,  RO,        "0x003002E6", "",      "",          "",      "Module 3"},
{SUB, 0xF010, 4, U32,  RO,        "0x004002E6", "",      "",          "",      "Module 4"},
{ARR, 0xF050, 0, U32,  RO,        "",           "",      "",          "",      "Detected Module List"},               // 7.2.104
{SUB, 0xF050, 1, U32,  RO,        "0x001002E6", "",      "",          "",      "1st detected Module"},
};
// clang-format on

// Value sets where the specification lists the only accepted values; anything else is "value range exceeded".
struct ValueSet {
    uint16_t index;
    uint8_t sub;
    int64_t values[16];
    uint8_t count;
};
template <std::size_t N>
constexpr ValueSet value_set(uint16_t index, uint8_t sub, const std::array<int8_t, N>& set) {
    static_assert(N <= 16);
    ValueSet v{index, sub, {}, static_cast<uint8_t>(N)};
    for (std::size_t k = 0; k < N; ++k)
        v.values[k] = set[k];
    return v;
}
// clang-format off
constexpr ValueSet kValueSets[] = {
    {0x1C32, 1, {1, 2}, 2},                                                     // 7.2.17.1, T7-76
    {0x1C33, 1, {1, 2, 34}, 3},                                                 // 7.2.18.1, T7-79
    {0x3000, 2, {0x01, 0x11, 0x21, 0x31}, 4},                                   // T7-88
    {0x3000, 3, {0x00, 0x30, 0x31, 0x32}, 4},                                   // T7-90
    value_set(0x6060, 0, kModesOfOperation),                                     // T7-123
    value_set(0x6098, 0, drive::kHomingMethods),                                // T7-126
    {0x6402, 0, {1, 10}, 2},                                                    // T7-139
};
// clang-format on

// The rows that hold a vendor parameter, as the drive's bindings; each row's type is the parameter's.
constexpr std::size_t kBindingCount = [] {
    std::size_t n = 0;
    for (const Line& l : kTable)
        if (l.binds) ++n;
    return n;
}();
constexpr std::array<drive::Binding, kBindingCount> kBindings = [] {
    std::array<drive::Binding, kBindingCount> out{};
    std::size_t n = 0;
    for (const Line& l : kTable)
        if (l.binds) out[n++] = drive::Binding{l.param, l.index, l.kind == VAR ? uint8_t{0} : l.sub};
    return out;
}();
constexpr bool bindings_typed() {
    for (const Line& l : kTable)
        if (l.binds && (bit_size(l.type) != 8 * drive::param_size(l.param) ||
                        is_signed(l.type) != drive::param_signed(l.param)))
            return false;
    return true;
}
static_assert(bindings_typed(), "a P(...) row's type differs from the drive parameter's");
constexpr bool bindings_unique() {
    for (std::size_t i = 0; i < kBindings.size(); ++i)
        for (std::size_t k = i + 1; k < kBindings.size(); ++k)
            if (kBindings[i].param == kBindings[k].param) return false;
    return true;
}
static_assert(bindings_unique(), "a drive parameter is held by two rows");

// What a master may write only in "Power Disable" (§7.2.22-7.2.29, §7.2.78-7.2.80, §7.2.100): the axis
// configuration, of the motor data only the pole pairs, the sensor records, the SI units, the motor type.
constexpr drive::PowerDisableOnly kPowerDisableOnly[] = {
    {0x3000}, {0x3001, 3}, {0x3010}, {0x3011}, {0x3012}, {0x3014},
    {0x301A}, {0x3020},    {0x60A8}, {0x60A9}, {0x60AA}, {0x6402},
};

std::string identity_token(std::string_view token, const Identity& id) {
    auto hex = [](uint32_t v) {
        char b[16];
        std::snprintf(b, sizeof b, "0x%08X", v);
        return std::string(b);
    };
    if (token == "$vendor_id") return hex(id.vendor_id);
    if (token == "$product_code") return hex(id.product_code);
    if (token == "$revision") return hex(id.revision);
    if (token == "$serial_number") return hex(id.serial_number);
    if (token == "$device_name") return id.device_name;
    if (token == "$hardware_version") return id.hardware_version;
    if (token == "$software_version") return id.software_version;
    throw std::logic_error("od: unknown identity token " + std::string(token));
}

Number parse_number(std::string_view s, DataType t, uint16_t index) {
    if (s.empty()) return {};
    bool neg = false;
    std::string_view d = s;
    if (d.front() == '-') {
        neg = true;
        d.remove_prefix(1);
    }
    int base = 10;
    if (d.size() > 2 && d[0] == '0' && (d[1] == 'x' || d[1] == 'X')) {
        base = 16;
        d.remove_prefix(2);
    }
    uint64_t u = 0;
    auto [p, ec] = std::from_chars(d.data(), d.data() + d.size(), u, base);
    if (ec != std::errc() || p != d.data() + d.size()) {
        throw std::logic_error("od: bad number '" + std::string(s) + "' at " +
                               util::strprintf("0x%04X", index));
    }
    if (neg) return -static_cast<int64_t>(u);
    if (is_signed(t)) return static_cast<int64_t>(u);
    return u;
}

// The values an enumerated entry takes: its value set, a display's the value set of what it displays, or
// the range of its limits. Each must have a name (value_names.hpp), so the ESI names every value the
// drive accepts and no other.
std::vector<NamedValue> enumeration_of(const Entry& e) {
    if (!has_value_names(e.index, e.subindex)) return {};
    uint16_t index = e.index;
    uint8_t sub = e.subindex;
    if (index == 0x6061 && sub == 0) index = 0x6060;  // the display takes the modes of operation
    std::vector<int64_t> values;
    for (const ValueSet& vs : kValueSets)
        if (vs.index == index && vs.sub == sub) values.assign(vs.values, vs.values + vs.count);
    if (values.empty()) {
        const auto* lo = std::get_if<int64_t>(&e.minimum);
        const auto* hi = std::get_if<int64_t>(&e.maximum);
        const auto* ulo = std::get_if<uint64_t>(&e.minimum);
        const auto* uhi = std::get_if<uint64_t>(&e.maximum);
        const int64_t a = lo ? *lo : (ulo ? static_cast<int64_t>(*ulo) : 0);
        const int64_t b = hi ? *hi : (uhi ? static_cast<int64_t>(*uhi) : -1);
        if ((lo || ulo) && (hi || uhi) && b - a < 256)
            for (int64_t v = a; v <= b; ++v)
                values.push_back(v);
    }
    std::string where = "0x";
    for (int shift = 12; shift >= 0; shift -= 4)
        where += "0123456789ABCDEF"[(e.index >> shift) & 0xF];
    where += ':';  // (appended, not "literal" + temporary: GCC 12 -O3 -Wrestrict false positive)
    where += std::to_string(e.subindex);
    if (values.empty())
        throw std::logic_error("od: " + where + " has value names but no value set or limits");
    std::vector<NamedValue> out;
    for (int64_t v : values) {
        const std::string_view text = value_name(e.index, e.subindex, v);
        if (text.empty())
            throw std::logic_error("od: " + where + " takes " + std::to_string(v) + " but it has no name");
        out.push_back({v, std::string(text)});
    }
    return out;
}

Entry make_entry(const Line& l, const Identity& id) {
    Entry e;
    e.index = l.index;
    e.subindex = l.kind == VAR ? 0 : l.sub;
    e.name = l.name;
    e.type = l.type;
    e.access = l.acc;
    e.unit = l.unit;
    std::string def = l.def;
    if (!def.empty() && def.front() == '$') def = identity_token(def, id);
    if (is_string(l.type)) {
        e.default_string = def;
        std::size_t cap = def.size();
        if (*l.max) cap = std::max<std::size_t>(cap, std::strtoul(l.max, nullptr, 10));
        e.bit_length = static_cast<uint16_t>(8 * std::max<std::size_t>(cap, 1));
    } else {
        e.default_value = parse_number(def, l.type, l.index);
        e.minimum = parse_number(l.min, l.type, l.index);
        e.maximum = parse_number(l.max, l.type, l.index);
        e.enumeration = enumeration_of(e);
    }
    return e;
}

// Sum of the bit lengths of the default entries of a PDO mapping object.
uint32_t default_pdo_bits(uint16_t pdo) {
    uint64_t count = 0;
    for (const Line& l : kTable)
        if (l.kind == SUB && l.index == pdo && l.sub == 0)
            count = std::get<uint64_t>(parse_number(l.def, U8, pdo));
    uint32_t bits = 0;
    for (const Line& l : kTable)
        if (l.kind == SUB && l.index == pdo && l.sub >= 1 && l.sub <= count)
            bits += static_cast<uint32_t>(std::get<uint64_t>(parse_number(l.def, U32, pdo)) & 0xFF);
    return bits;
}

}  // namespace

DeviceDescription description() {
    DeviceDescription d;
    Identity& id = d.identity;
    id.vendor_id = 0x000000FB;     // 7.2.4.2
    id.product_code = 0x30010000;  // hardware version 3001h (MAXPOS 50/5, T7-64), application number 0
    id.revision = 0x01200000;      // software version 0120h, application version 0
    id.serial_number = 0;
    id.vendor_name = "maxon motor ag";
    id.device_name = "MAXPOS";  // 7.2.3
    id.hardware_version = "3001h";
    id.software_version = "0120h";
    id.order_code = "MAXPOS 50/5";
    id.group_type = "Drives";
    d.standard_mailbox = {0x1000, 128, 0x1080, 128};
    d.bootstrap_mailbox = {0x1000, 1024, 0x1400, 1024};
    d.mailbox_protocols = mailbox_protocol::CoE | mailbox_protocol::FoE;
    d.foe_details = 0x01;
    place_sync_managers(d);
    d.dc_modes = {
        {"SM-Synchron", "SM-Synchronous (SM2 event)", 0x0000, 1, 0},
        {"DC", "DC-Synchronous (SYNC0)", 0x0300, 1, 0},
    };
    d.eeprom_bytes = 2048;
    // The four RxPDOs (CSP, CSV, CST, PPM/PVM; 7.2.6-7.2.9) each map the controlword and the mode, so one
    // of them is assigned at a time, and likewise the four TxPDOs with the statusword (7.2.10-7.2.13).
    // None is mandatory: 0x1C12/0x1C13 may hold any one of them, or none (count 0, "PDO disabled").
    // The mappings are writable in Pre-Op, so no PDO is Fixed. See docs/decisions/coe.md.
    for (const uint16_t base : {uint16_t{0x1600}, uint16_t{0x1A00}})
        for (uint16_t i = 0; i < 4; ++i) {
            PdoRule rule;
            rule.pdo = static_cast<uint16_t>(base + i);
            for (uint16_t j = 0; j < 4; ++j)
                if (j != i) rule.exclude.push_back(static_cast<uint16_t>(base + j));
            d.pdo_rules.push_back(std::move(rule));
        }
    // One predefined set per pair, named after the mode its mappings serve (7.2.6-7.2.13).
    d.pdo_sets = {
        {"Cyclic synchronous position (CSP)", {0x1600}, {0x1A00}},
        {"Cyclic synchronous velocity (CSV)", {0x1601}, {0x1A01}},
        {"Cyclic synchronous torque (CST)", {0x1602}, {0x1A02}},
        {"Profile position / velocity (PPM, PVM)", {0x1603}, {0x1A03}},
    };
    // A request leaves SM0 at the next poll; the slowest answer is a 0x1010 save (file write and fsync).
    d.mailbox_request_timeout_ms = 100;
    d.mailbox_response_timeout_ms = 2000;
    // The drive core's diagnosis texts (ETG.1020 text ids, ETG.2000 DiagMessages): its own messages, then one
    // per error it can raise (§8.1, Table 8-141), whose 0x10F3 message carries the text's id.
    static const char* const kClass[] = {"information", "warning", "error"};
    for (const drive::DiagText& t : drive::kDiagTexts)
        d.diag_messages.push_back({t.id, std::string(t.text), kClass[t.type < 3 ? t.type : 0], 0});
    for (const drive::ErrorInfo& e : drive::kErrorTable)
        d.diag_messages.push_back({drive::error_text_id(e.code), std::string(e.name), "error", e.code});
    return d;
}

void place_sync_managers(DeviceDescription& d) {
    // Largest process-data image: 4 assigned PDOs of 10 entries of 32 bits (7.2.6-7.2.16).
    constexpr uint32_t kMaxPdoBytes = 4 * 10 * 4;
    auto round_up = [](uint32_t v, uint32_t a) { return (v + a - 1) / a * a; };
    const MailboxLayout& m = d.standard_mailbox;
    const uint32_t mbx_end =
        std::max<uint32_t>(uint32_t{m.out_start} + m.out_size, uint32_t{m.in_start} + m.in_size);
    const uint32_t sm2 = round_up(mbx_end, 0x80);
    const uint32_t sm3 = round_up(sm2 + 3 * kMaxPdoBytes, 0x80);
    if (sm3 + 3 * kMaxPdoBytes > 0x10000)
        throw std::out_of_range("maxpos: no room for the process-data SyncManagers after the mailbox");
    const auto rx_bytes = static_cast<uint16_t>((default_pdo_bits(0x1600) + 7) / 8);
    const auto tx_bytes = static_cast<uint16_t>((default_pdo_bits(0x1A00) + 7) / 8);
    // SM0..SM3 in the order of 0x1C00, each with its kind's control byte.
    const auto sm = [&](std::size_t n, uint16_t start, uint16_t size, uint16_t min, uint16_t max) {
        const SmKind k = kSmCommunicationTypes[n];
        return SyncManagerDefault{k, start, size, default_sm_control(k), true, min, max};
    };
    d.sync_managers = {
        // A mailbox SyncManager must have exactly the mailbox's size (ecat/ checks it on Init -> Pre-Op).
        sm(0, m.out_start, m.out_size, m.out_size, m.out_size),
        sm(1, m.in_start, m.in_size, m.in_size, m.in_size),
        sm(2, static_cast<uint16_t>(sm2), rx_bytes, 0, kMaxPdoBytes),
        sm(3, static_cast<uint16_t>(sm3), tx_bytes, 0, kMaxPdoBytes),
    };
}

Dictionary dictionary(const DeviceDescription& description) {
    Dictionary dict;
    const Identity& id = description.identity;
    std::size_t i = 0;
    const std::size_t n = std::size(kTable);
    while (i < n) {
        const Line& head = kTable[i];
        Object o;
        o.index = head.index;
        o.name = head.name;
        o.type = head.type;
        if (head.kind == VAR) {
            o.code = ObjectCode::Var;
            o.entries.push_back(make_entry(head, id));
            ++i;
        } else if (head.kind == ARR || head.kind == REC) {
            o.code = head.kind == ARR ? ObjectCode::Array : ObjectCode::Record;
            for (++i; i < n && kTable[i].kind == SUB && kTable[i].index == head.index; ++i)
                o.entries.push_back(make_entry(kTable[i], id));
        } else {
            throw std::logic_error("od: subindex line without its object header");
        }
        dict.add(std::move(o));
    }
    for (const ValueSet& vs : kValueSets) {
        const uint8_t sub = vs.sub;
        dict.add_validator(vs.index, [vs, sub](const Entry& e, std::span<const uint8_t> v) {
            if (e.subindex != sub) return Status::Ok;
            int64_t x = 0;
            if (is_signed(e.type)) {
                uint64_t u = 0;
                for (std::size_t k = 0; k < v.size(); ++k)
                    u |= uint64_t{v[k]} << (8 * k);
                const unsigned bits = static_cast<unsigned>(8 * v.size());
                if (bits < 64 && ((u >> (bits - 1)) & 1u)) u |= ~uint64_t{0} << bits;
                x = static_cast<int64_t>(u);
            } else {
                for (std::size_t k = 0; k < v.size(); ++k)
                    x |= int64_t{v[k]} << (8 * k);
            }
            for (uint8_t k = 0; k < vs.count; ++k)
                if (vs.values[k] == x) return Status::Ok;
            return Status::InvalidValue;
        });
    }
    return dict;
}

DeviceDescription parse_config(std::string_view text, const std::string& source) {
    return parse_device_config(text, source, description(), place_sync_managers);
}

DeviceDescription load_config(const std::filesystem::path& path) {
    return load_device_config(path, description(), place_sync_managers);
}

Product product(const std::filesystem::path& config_file) {
    Product p;
    p.source = config_file.empty() ? "the built-in MAXPOS" : "the MAXPOS of " + config_file.string();
    p.description = config_file.empty() ? description() : load_config(config_file);
    p.make_dictionary = [](const DeviceDescription& d) { return dictionary(d); };
    p.application = Application::Cia402Drive;
    return p;
}

const drive::VendorObjects& drive_objects() {
    static const drive::VendorObjects objects{kBindings, kPowerDisableOnly};
    return objects;
}

}  // namespace maxpos
