// The type-erased list of the CiA 402 handles and the names of the vendor parameters.
#include "drive/objects.hpp"

#include <type_traits>

namespace drive {
namespace {

#define DRIVE_OBJECT_INFO(name, idx, sub, T, def, role) \
    ObjInfo{#name, idx, sub, sizeof(T), std::is_signed_v<T>, Role::role, static_cast<int64_t>(T(def))},
const ObjInfo kInfo[] = {DRIVE_CIA402_OBJECTS(DRIVE_OBJECT_INFO)};
#undef DRIVE_OBJECT_INFO

}  // namespace

std::span<const ObjInfo> cia402_objects() {
    return kInfo;
}

std::string_view param_name(Param p) {
    switch (p) {
#define DRIVE_PARAM_NAME(name, T, def, role) \
    case Param::name:                        \
        return #name;
        DRIVE_VENDOR_PARAMETERS(DRIVE_PARAM_NAME)
#undef DRIVE_PARAM_NAME
    }
    return {};
}

}  // namespace drive
