#pragma once
// The ENI reader (ETG.2100 EtherCAT Network Information: the EtherCATConfig XML that TwinCAT and EC-Engineer
// export for a master): per Config/Slave, in the order of the line, what the master was configured with:
// identity and addresses, process data (SyncManagers, PDOs, the slave's bits in the process image), mailbox
// and its CoE init commands, the register init commands, the wiring (PreviousPort) and distributed clocks;
// the Master section and the cyclic frames (the working counters the master expects) for the tests.
// Independent of the object model (od/), like the ESI reader: target `eni_reader`.
//
// Numbers are written as ETG.2100 (xs:int / HexDecValue) has them: decimal, negative where a 32-bit
// identifier has its top bit set, or "#x..." hexadecimal. Every value read is checked against its field;
// a bad file throws EniError "FILE:LINE: message".
#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace esi::eni {

// The largest ENI read: a line of a thousand slaves with their init commands is a few MiB.
inline constexpr std::size_t kMaxEniBytes = std::size_t{32} << 20;

class EniError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

// One EtherCAT datagram of an InitCmd or a cyclic Cmd (ETG.1000.4 command codes: 1 APRD, 2 APWR, 4 FPRD,
// 5 FPWR, 7 BRD, 8 BWR, 10 LRD, 11 LWR, 12 LRW, ...).
struct InitCmd {
    std::vector<std::string> transitions;  // "IP", "PS", "SO", "OI", ... (Transition, repeated)
    std::string comment;
    uint8_t cmd = 0;
    uint16_t adp = 0;              // Adp (position or station address)
    uint16_t ado = 0;              // Ado (register)
    std::optional<uint32_t> addr;  // Addr (logical) instead of Adp/Ado
    std::vector<uint8_t> data;     // Data (hex), or DataLength zeros
    std::optional<uint16_t> cnt;   // Cnt: the working counter expected
    uint16_t retries = 0;
    int line = 0;
};

// A CoE init command (Mailbox/CoE/InitCmds/InitCmd): an SDO transfer the master does in a transition.
struct CoeInitCmd {
    std::vector<std::string> transitions;
    std::string comment;
    uint8_t ccs = 0;  // 1 download (write), 2 upload (read)
    uint16_t index = 0;
    uint8_t subindex = 0;
    std::vector<uint8_t> data;
    bool complete_access = false;
    bool fixed = false;
    bool disabled = false;
    uint32_t timeout_ms = 0;
    int line = 0;
};

struct MailboxArea {
    uint16_t start = 0;
    uint16_t length = 0;
};

struct Mailbox {
    bool present = false;
    MailboxArea send;  // master -> slave (SM0)
    MailboxArea recv;  // slave -> master (SM1)
    std::optional<MailboxArea> bootstrap_send, bootstrap_recv;
    std::vector<std::string> protocols;  // as written: AoE, EoE, CoE, FoE, SoE, VoE
    std::vector<CoeInitCmd> coe_init_cmds;
    // Init commands of protocols other than CoE (EoE/SoE/AoE/FoE/VoE InitCmds): counted per protocol.
    std::vector<std::pair<std::string, int>> other_init_cmds;
    int line = 0;
    // SII word 0x1C bits of the protocols (AoE 1, EoE 2, CoE 4, FoE 8, SoE 0x10, VoE 0x20).
    uint16_t protocol_bits() const;
    bool has(const std::string& protocol) const;
};

// ProcessData/Sm0..Sm7 (the SyncManager as the master sets it up).
struct Sm {
    int number = 0;
    std::string type;  // MBoxOut, MBoxIn, Outputs, Inputs
    uint16_t start = 0;
    uint16_t default_size = 0;
    std::optional<uint16_t> min_size, max_size;
    uint8_t control = 0;
    bool enable = false;
    std::vector<uint16_t> pdos;  // Pdo: the PDOs assigned to it
    int line = 0;
};

struct PdoEntry {
    uint16_t index = 0;  // 0: a gap (padding)
    uint8_t subindex = 0;
    uint16_t bit_len = 0;
    std::string name;
    std::string data_type;  // empty for a gap
};

struct Pdo {
    bool rx = false;  // RxPdo (outputs) or TxPdo (inputs)
    uint16_t index = 0;
    std::optional<int> sm;  // Sm attribute: the SyncManager it is assigned to
    bool fixed = false;
    bool mandatory = false;
    std::string name;
    std::vector<PdoEntry> entries;
    int line = 0;
    unsigned bits() const;
};

// A slave's part of the process image: BitStart/BitLength of Send (outputs) and Recv (inputs).
struct BitRange {
    uint32_t start = 0;
    uint32_t length = 0;
};

struct ProcessData {
    std::vector<BitRange> send, recv;
    std::vector<Sm> sms;  // in the order written
    std::vector<Pdo> rxpdos, txpdos;
    const Sm* sm(int number) const;
    const Pdo* pdo(uint16_t index) const;
};

// PreviousPort: where the slave is plugged in (the port of the slave upstream, by its station address).
struct PreviousPort {
    bool selected = false;
    int port = 0;  // A 0, B 1, C 2, D 3
    uint16_t phys_addr = 0;
    int line = 0;
};

struct Dc {
    bool present = false;
    bool potential_reference_clock = false;
    bool reference_clock = false;
    std::optional<uint32_t> cycle_time0;
    std::optional<int32_t> cycle_time1;
    std::optional<int32_t> shift_time0;  // ShiftTime0 (or ShiftTime)
    std::optional<int32_t> shift_time1;
    std::optional<uint16_t> assign_activate;  // DC/AssignActivate where written (EC-Engineer)
    int line = 0;
};

struct SlaveInfo {
    std::string name;
    uint16_t phys_addr = 0;  // the station address the master gives it
    std::optional<uint16_t> auto_inc_addr;
    uint32_t vendor_id = 0;
    uint32_t product_code = 0;
    uint32_t revision = 0;
    uint32_t serial = 0;
    std::string physics;  // one letter per port: Y (MII), K (E-Bus), ' ' (none)
};

struct Slave {
    SlaveInfo info;
    ProcessData process_data;
    Mailbox mailbox;
    std::vector<InitCmd> init_cmds;
    std::vector<PreviousPort> previous_ports;
    Dc dc;
    int line = 0;  // the <Slave> element
    // The PreviousPort the master uses (the selected one, or the only one); null for the first slave.
    const PreviousPort* previous_port() const;
    // The value the master activates the DC unit with: the data of the init command writing register 0x0981
    // (or 0x0980 as a 16-bit word, high byte 0x0981), else DC/AssignActivate; nothing if neither.
    std::optional<uint16_t> assign_activate() const;
    // The bytes of the process image this slave's outputs (Send) and inputs (Recv) take, from the bit ranges.
    uint32_t output_bits() const;
    uint32_t input_bits() const;
};

struct CyclicCmd {
    std::string state;  // State (e.g. "PREOP SAFEOP OP" or one per element, joined by blanks)
    std::string comment;
    uint8_t cmd = 0;
    uint16_t adp = 0, ado = 0;
    std::optional<uint32_t> addr;
    uint16_t data_length = 0;
    std::optional<uint16_t> cnt;  // the working counter the master expects
    std::optional<uint32_t> input_offs, output_offs;
    int line = 0;
};

struct Frame {
    std::vector<CyclicCmd> cmds;
};

struct Cyclic {
    std::optional<uint32_t> cycle_time;  // µs, where written
    std::vector<Frame> frames;
};

struct Master {
    std::string name;
    std::vector<uint8_t> destination, source;  // MAC addresses (hex), empty if absent
    std::vector<InitCmd> init_cmds;
};

struct Config {
    std::string file;  // as given, for messages
    Master master;
    std::vector<Slave> slaves;
    std::vector<Cyclic> cyclic;
    uint32_t input_bytes = 0, output_bytes = 0;  // ProcessImage/Inputs|Outputs/ByteSize
    // "FILE:LINE" of a line, for messages about the slaves.
    std::string where(int line) const;
    // Index of the slave with this station address, -1 if none.
    int find_phys_addr(uint16_t phys_addr) const;
};

// Reads the file (a regular file of at most kMaxEniBytes, util::read_input_file) or a text. Throws EniError
// with "FILE:LINE: message" (FILE alone where there is no line: unreadable, not XML).
Config read_eni_file(const std::string& path);
Config read_eni_text(const std::string& xml, const std::string& name = "eni.xml");

}  // namespace esi::eni
