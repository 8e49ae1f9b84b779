// The fault registry of `ecat-slave --fault` (device/faults.hpp, docs/decisions/faults.md).
#include "device/faults.hpp"

#include <array>
#include <iomanip>
#include <ostream>

#include "device/device.hpp"

namespace device {

namespace {

using F = Fault;

// clang-format off
constexpr std::array<FaultInfo, kFaultCount> kFaults{{
    {F::WkcAprd, "wkc-aprd",
     "APRD of a readable register answers with working counter 2 instead of 1",
     "ETG.1000.4 datagram APRD, working counter"},
    {F::AliasIgnored, "alias-ignored",
     "configured-address datagrams never match the station alias 0x0012, even with 0x0100 bit 24 set",
     "ETG.1000.4 configured station alias; ESC datasheet 0x0012/0x0100"},
    {F::FprdAnyAddress, "fprd-any-address",
     "FPRD is answered (data, working counter 1) whatever station address it carries",
     "ETG.1000.4 configured address, FPRD"},
    {F::SourceMacUnchanged, "source-mac-unchanged",
     "returned frames keep the source MAC as sent (bit 1 of its first byte not set)",
     "ETG.1000.4 frame processing, source address of returned frames"},
    {F::SiiChecksum, "sii-checksum",
     "SII word 7 (CRC of words 0-6) is read back wrong; the ESC itself loads its configuration",
     "ETG.2010 SII word 7 checksum"},
    {F::DcTimeFrozen, "dc-time-frozen",
     "the DC system time 0x0910 read by the master does not advance (stays at the offset 0x0920)",
     "ETG.1000.4 distributed clocks, system time; ESC datasheet 0x0910"},
    {F::Sync0Never, "sync0-never",
     "cyclic operation is accepted in 0x0981 but SYNC0 pulses never come (0x098E, AL event bit 2)",
     "ESC datasheet SYNC0 generation 0x0981-0x09A3; ETG.1020 DC synchronisation"},
    {F::BootstrapRefused, "bootstrap-refused",
     "Init -> Bootstrap is refused with 0x0013 although the SII announces FoE and a bootstrap mailbox",
     "ETG.1000.6 ESM transition Init -> Bootstrap; ETG.2010 bootstrap mailbox words 0x14-0x17"},
    {F::AlCodeMissing, "al-code-missing",
     "a refused transition sets the error indication (0x0130 bit 4) but leaves the AL status code 0x0134 at 0",
     "ETG.1000.6 AL status code"},
    {F::InvalidStateSilent, "invalid-state-silent",
     "an invalid state request (e.g. Init -> Op) is ignored instead of refused with 0x0011",
     "ETG.1000.6 ESM, invalid requested state change 0x0011"},
    {F::ErrorAckIgnored, "error-ack-ignored",
     "the error acknowledge bit (0x0120 bit 4) does not clear the error indication; only a request for Init does",
     "ETG.1000.6 ESM error acknowledge"},
    {F::WatchdogNever, "watchdog-never",
     "the process-data watchdog never takes Op back to Safe-Op with 0x001B when the outputs stop",
     "ETG.1000.6 ESM Op -> Safe-Op + error 0x001B, SyncManager watchdog"},
    {F::Sm2LengthUnchecked, "sm2-length-unchecked",
     "Pre-Op -> Safe-Op accepts an SM2 length that differs from the RxPDO size (no 0x001D)",
     "ETG.1000.6 AL status code 0x001D invalid output configuration"},
    {F::InputsOpOnly, "inputs-op-only",
     "TxPDO inputs are written to SM3 only in Op; in Safe-Op they are not valid",
     "ETG.1000.6 ESM Safe-Op: inputs valid"},
    {F::OutputsInSafeOp, "outputs-in-safeop",
     "RxPDO outputs are applied to the application in Safe-Op already",
     "ETG.1000.6 ESM Safe-Op: outputs in safe state"},
    {F::MbxCounterIgnored, "mbx-counter-ignored",
     "a mailbox request repeated with the same counter (1-7) is executed twice",
     "ETG.1000.4 mailbox header counter"},
    {F::MbxRepeatIgnored, "mbx-repeat-ignored",
     "the repeat request (SM1 activate 0x080E bit 1) is never answered: no acknowledge, no repeated reply",
     "ETG.1000.4 mailbox repeat request"},
    {F::MbxUnsupportedSilent, "mbx-unsupported-silent",
     "a request of a mailbox type the slave does not support gets no mailbox error reply (0x0002)",
     "ETG.1000.4 mailbox error reply, unsupported protocol"},
    {F::IdentityMismatch, "identity-mismatch",
     "0x1018:02 (product code) is the SII's product code + 1",
     "ETG.1000.6 / ETG.2010 identity object 0x1018 and SII words 0x08-0x0F"},
    {F::AbortMissingObject, "abort-missing-object",
     "an SDO access to a missing object aborts with 0x06090011 instead of 0x06020000",
     "ETG.1000.6 SDO abort codes"},
    {F::AbortCommandDownload, "abort-command-download",
     "the abort of a failed SDO download carries the request's command byte instead of 0x80",
     "ETG.1000.6 Abort SDO Transfer, command specifier 4"},
    {F::ReadOnlyWriteConfirmed, "readonly-write-confirmed",
     "an SDO download to a read-only entry is confirmed (value unchanged) instead of aborted 0x06010002",
     "ETG.1000.6 SDO download, abort 0x06010002"},
    {F::RangeUnchecked, "range-unchecked",
     "an SDO download outside the entry's limits is confirmed (value unchanged) instead of aborted 0x06090031/32",
     "ETG.1000.6 SDO abort codes 0x06090031/0x06090032"},
    {F::PdoMapInSafeOp, "pdo-map-in-safeop",
     "PDO mapping and assignment objects (0x16xx, 0x1Axx, 0x1C12, 0x1C13) are written in Safe-Op",
     "ETG.1000.6 PDO mapping/assignment only in Pre-Op, abort 0x08000022"},
    {F::ExpeditedSizeWrong, "expedited-size-wrong",
     "expedited upload responses say 4 bytes (size bits 0) whatever the object's size",
     "ETG.1000.6 SDO upload expedited response, size indicator"},
    {F::UploadToggleStuck, "upload-toggle-stuck",
     "segmented upload responses always carry toggle bit 0",
     "ETG.1000.6 SDO upload segment, toggle bit"},
    {F::DownloadToggleUnchecked, "download-toggle-unchecked",
     "download segments with a wrong toggle bit are taken instead of aborted 0x05030000",
     "ETG.1000.6 SDO download segment, abort 0x05030000"},
    {F::CaNoPadding, "ca-no-padding",
     "complete-access upload from subindex 0 sends subindex 0 as 8 bits, without its padding byte",
     "ETG.1000.6 SDO complete access, subindex 0 as 16 bits"},
    {F::InfoErrorShort, "info-error-short",
     "the SDO information error reply is 2 bytes short (abort code cut to 16 bits)",
     "ETG.1000.6 SDO Info Error Request"},
    {F::InfoWrongType, "info-wrong-type",
     "entry descriptions of subindex > 0 give data type UNSIGNED8 (0x0005) whatever the entry's type",
     "ETG.1000.6 SDO information entry description"},
    {F::FoePasswordIgnored, "foe-password-ignored",
     "an FoE write with a wrong password is accepted instead of refused with error 0x800A",
     "ETG.1000.6 FoE write request, error code 0x800A no rights"},
    {F::FoeAnyFile, "foe-any-file",
     "an FoE write to a file name the device does not know is accepted instead of refused with 0x8001",
     "ETG.1000.6 FoE write request, error code 0x8001 not found"},
    {F::QuickStopIgnored, "quickstop-ignored",
     "the quick stop command in Operation enabled is ignored (no transition 11, 0x605A not applied)",
     "IEC 61800-7-201/CiA 402 device control, transition 11, 0x605A"},
    {F::FaultResetIgnored, "fault-reset-ignored",
     "the fault reset edge (controlword bit 7) does not take the drive out of Fault",
     "IEC 61800-7-201/CiA 402 device control, transition 15"},
    {F::ModeDisplayStuck, "mode-display-stuck",
     "0x6061 keeps showing the first mode of operation, whatever 0x6060 selects later",
     "IEC 61800-7-201/CiA 402 0x6060/0x6061 modes of operation"},
}};
// clang-format on

constexpr bool catalogue_in_enum_order() {
    for (std::size_t i = 0; i < kFaults.size(); ++i)
        if (static_cast<std::size_t>(kFaults[i].fault) != i) return false;
    return true;
}
static_assert(catalogue_in_enum_order(), "kFaults must list every Fault in enum order");

std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t'))
        s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t'))
        s.remove_suffix(1);
    return s;
}

}  // namespace

std::span<const FaultInfo> fault_catalogue() {
    return kFaults;
}

const FaultInfo& fault_info(Fault fault) {
    return kFaults[static_cast<std::size_t>(fault)];
}

std::optional<Fault> find_fault(std::string_view name) {
    for (const FaultInfo& f : kFaults)
        if (f.name == name) return f.fault;
    return std::nullopt;
}

std::optional<std::string> add_faults(std::string_view list, FaultSet& set) {
    while (true) {
        const std::size_t comma = list.find(',');
        const std::string_view name = trim(list.substr(0, comma));
        const auto fault = find_fault(name);
        if (!fault) return std::string(name);
        set.set(static_cast<std::size_t>(*fault));
        if (comma == std::string_view::npos) return std::nullopt;
        list.remove_prefix(comma + 1);
    }
}

void print_faults(std::ostream& out) {
    std::size_t width = 0;
    for (const FaultInfo& f : kFaults)
        width = std::max(width, f.name.size());
    for (const FaultInfo& f : kFaults)
        out << std::left << std::setw(static_cast<int>(width)) << f.name << "  " << f.description << " ("
            << f.clause << ")\n";
}

void apply_faults(const FaultSet& set, esc::EscFaults& esc, DeviceFaults& device) {
    auto on = [&set](Fault f) { return set.test(static_cast<std::size_t>(f)); };
    auto flag = [&](Fault f, bool& target) {
        if (on(f)) target = true;
    };
    flag(F::WkcAprd, esc.wkc_aprd);
    flag(F::AliasIgnored, esc.alias_ignored);
    flag(F::FprdAnyAddress, esc.fprd_any_address);
    flag(F::SourceMacUnchanged, esc.source_mac_unchanged);
    flag(F::SiiChecksum, esc.sii_checksum_wrong);
    flag(F::DcTimeFrozen, esc.dc_time_frozen);
    flag(F::Sync0Never, esc.sync0_never);

    ecat::StackFaults& s = device.stack;
    flag(F::BootstrapRefused, s.bootstrap_refused);
    flag(F::AlCodeMissing, s.al_code_missing);
    flag(F::InvalidStateSilent, s.invalid_request_silent);
    flag(F::ErrorAckIgnored, s.error_ack_ignored);
    flag(F::WatchdogNever, s.watchdog_ignored);
    flag(F::Sm2LengthUnchecked, s.sm2_length_unchecked);
    flag(F::InputsOpOnly, s.inputs_op_only);
    flag(F::OutputsInSafeOp, s.outputs_in_safe_op);
    flag(F::MbxCounterIgnored, s.mailbox.counter_ignored);
    flag(F::MbxRepeatIgnored, s.mailbox.repeat_ignored);
    flag(F::MbxUnsupportedSilent, s.mailbox.unsupported_protocol_silent);

    flag(F::IdentityMismatch, device.identity_mismatch);
    coe::CoeFaults& c = device.coe;
    flag(F::AbortMissingObject, c.abort_missing_object);
    flag(F::AbortCommandDownload, c.download_abort_command);
    flag(F::ReadOnlyWriteConfirmed, c.read_only_write_confirmed);
    flag(F::RangeUnchecked, c.value_range_unchecked);
    flag(F::PdoMapInSafeOp, c.pdo_map_in_safe_op);
    flag(F::ExpeditedSizeWrong, c.expedited_size_wrong);
    flag(F::UploadToggleStuck, c.upload_toggle_stuck);
    flag(F::DownloadToggleUnchecked, c.download_toggle_unchecked);
    flag(F::CaNoPadding, c.ca_no_padding);
    flag(F::InfoErrorShort, c.info_error_short);
    flag(F::InfoWrongType, c.info_entry_wrong_type);

    flag(F::FoePasswordIgnored, device.foe.password_ignored);
    flag(F::FoeAnyFile, device.foe.any_file_name);

    flag(F::QuickStopIgnored, device.axis.quick_stop_ignored);
    flag(F::FaultResetIgnored, device.axis.fault_reset_ignored);
    flag(F::ModeDisplayStuck, device.axis.mode_display_stuck);
}

}  // namespace device
