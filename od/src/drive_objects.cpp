// The type-erased list of the drive's object handles and the defaults the object table takes from them.
#include "od/drive_objects.hpp"

#include <type_traits>

namespace od {
namespace {

template <typename T>
constexpr Number number(T v) {
    if constexpr (std::is_signed_v<T>)
        return Number{static_cast<int64_t>(v)};
    else
        return Number{static_cast<uint64_t>(v)};
}

#define OD_DRIVE_OBJECT_INFO(name, idx, sub, T, def, role) \
    ObjInfo{#name, idx, sub, sizeof(T), std::is_signed_v<T>, Role::role, number<T>(def)},
const ObjInfo kInfo[] = {OD_DRIVE_OBJECTS(OD_DRIVE_OBJECT_INFO)};
#undef OD_DRIVE_OBJECT_INFO

}  // namespace

std::span<const ObjInfo> drive_objects() {
    return kInfo;
}

std::optional<Number> declared_default(uint16_t index, uint8_t sub) {
    for (const ObjInfo& o : kInfo)
        if (o.index == index && o.sub == sub) return o.def;
    if (index == obj::SupportedHomingMethods && sub >= 1 && sub <= kHomingMethods.size())
        return number<int64_t>(kHomingMethods[sub - 1u]);
    if (index == obj::SupportedDriveModes && sub == 0) return number<uint32_t>(supported_drive_modes());
    if (index == obj::SyncManagerCommunicationType) {
        if (sub == 0) return number<uint64_t>(kSmCommunicationTypes.size());
        if (sub <= kSmCommunicationTypes.size())
            return number<uint64_t>(static_cast<uint8_t>(kSmCommunicationTypes[sub - 1u]));
    }
    return std::nullopt;
}

}  // namespace od
