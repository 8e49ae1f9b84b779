#pragma once
// `ecat-slave --fault NAME`: deliberate deviations from the standards, a testing aid for conformance tools
// (docs/decisions/faults.md). Each fault breaks exactly one observable behaviour, as a slave developer's bug
// would, and nothing else. This is the one registry of their names; each layer has its own flags
// (esc::EscFaults, ecat::StackFaults, coe::CoeFaults, foe::FoeFaults, drive::AxisFaults, DeviceFaults) and
// apply_faults() sets them, so no layer learns about another.
#include <bitset>
#include <cstddef>
#include <iosfwd>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "esc/faults.hpp"

namespace device {

struct DeviceFaults;

enum class Fault : unsigned {
    // ESC and data link
    WkcAprd,
    AliasIgnored,
    FprdAnyAddress,
    SourceMacUnchanged,
    SiiChecksum,
    DcTimeFrozen,
    Sync0Never,
    // State machine, mailbox, process data
    BootstrapRefused,
    AlCodeMissing,
    InvalidStateSilent,
    ErrorAckIgnored,
    WatchdogNever,
    Sm2LengthUnchecked,
    InputsOpOnly,
    OutputsInSafeOp,
    MbxCounterIgnored,
    MbxRepeatIgnored,
    MbxUnsupportedSilent,
    // CoE
    IdentityMismatch,
    AbortMissingObject,
    AbortCommandDownload,
    ReadOnlyWriteConfirmed,
    RangeUnchecked,
    PdoMapInSafeOp,
    ExpeditedSizeWrong,
    UploadToggleStuck,
    DownloadToggleUnchecked,
    CaNoPadding,
    InfoErrorShort,
    InfoWrongType,
    // FoE
    FoePasswordIgnored,
    FoeAnyFile,
    // CiA 402
    QuickStopIgnored,
    FaultResetIgnored,
    ModeDisplayStuck,
    Count
};
inline constexpr std::size_t kFaultCount = static_cast<std::size_t>(Fault::Count);
using FaultSet = std::bitset<kFaultCount>;

struct FaultInfo {
    Fault fault;
    std::string_view name;         // what --fault takes
    std::string_view description;  // the one behaviour it breaks
    std::string_view clause;       // where the standard says what the right behaviour is
};

// Every fault, in the order of the enum.
std::span<const FaultInfo> fault_catalogue();
const FaultInfo& fault_info(Fault fault);
std::optional<Fault> find_fault(std::string_view name);

// Adds the faults of a comma-separated list ("a,b", spaces around names ignored) to set. Returns the first
// unknown name, or nullopt if every name was known. "list" is not a fault (the caller prints the catalogue).
std::optional<std::string> add_faults(std::string_view list, FaultSet& set);
// "name  description (clause)" lines, one per fault.
void print_faults(std::ostream& out);

// Sets the layers' flags of every fault in set (flags of faults not in set are left alone).
void apply_faults(const FaultSet& set, esc::EscFaults& esc, DeviceFaults& device);

}  // namespace device
