#pragma once
// The conformance suite's core: test cases, outcomes, the catalogue, and the run context (the master, the
// slave under test, what its SII, CoE and ESI say). The tests themselves live in tests_<group>.cpp.
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "esc/link.hpp"
#include "esi/esi_reader.hpp"
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"

namespace conform {

// How long (scaled by --timeout-scale) a slave that stopped answering is waited for before it is called lost:
// between two tests, and in each read of the set-up. A busy host may deschedule the slave (or this tool) for
// a few hundred milliseconds; a slave that is gone is still reported within it.
inline constexpr int kAnswerGraceMs = 1000;

// The ESI reader is the project's one od-free reader (esi/esi_reader.hpp, target esi_reader).
using esi::esi_basic_bits;
using esi::esi_coe_type;
using esi::EsiCoe;
using esi::EsiDevice;
using esi::EsiEntry;
using esi::EsiFile;
using esi::EsiObject;
using esi::EsiOpMode;
using esi::EsiPdo;
using esi::EsiPdoEntry;
using esi::EsiSm;
using esi::parse_esi_number;
using esi::read_esi_file;
using esi::read_esi_text;

enum class Status : uint8_t { Pass, Fail, Skip, Warn };
enum class Severity : uint8_t { Error, Warning };

struct Outcome {
    Status status = Status::Pass;
    std::string message;  // why it failed / was skipped; what was checked when it passed
    std::string observed;
    std::string expected;
};

Outcome pass(std::string what = {}, std::string observed = {});
Outcome fail(std::string message, std::string observed = {}, std::string expected = {});
Outcome skip(std::string reason);
// Compares and fails with both values when they differ.
Outcome expect_eq(const std::string& what, const std::string& observed, const std::string& expected);

class Context;

struct TestCase {
    std::string id;     // group.subject.aspect, stable
    std::string group;  // esc, sii, esm, mbx, sdo, sdoinfo, pd, dc, foe, cia402
    std::string title;
    std::string clause;  // the standard and subject the test checks
    Severity severity = Severity::Error;
    std::string applies;  // when the test applies (else it is skipped), for the catalogue
    std::function<Outcome(Context&)> run;
};

struct TestResult {
    const TestCase* test = nullptr;
    Outcome outcome;
    std::chrono::microseconds duration{0};
    int slave = -1;  // position of the slave it ran on, with --slave all or a list (-1: the one slave)
};

using Catalogue = std::vector<TestCase>;
// Every test of every group, in the order they run.
Catalogue build_catalogue();
const std::vector<std::string>& group_names();
std::string group_title(const std::string& group);

// Adders, one per tests_<group>.cpp.
void add_esc_tests(Catalogue& c);
void add_sii_tests(Catalogue& c);
void add_esm_tests(Catalogue& c);
void add_mbx_tests(Catalogue& c);
void add_sdo_tests(Catalogue& c);
void add_sdoinfo_tests(Catalogue& c);
void add_pd_tests(Catalogue& c);
void add_io_tests(Catalogue& c);    // pd: inputs refreshed (tests_io.cpp)
void add_emcy_tests(Catalogue& c);  // mbx: emergency of a device that is not a drive (tests_emcy.cpp)
void add_dc_tests(Catalogue& c);
void add_foe_tests(Catalogue& c);
void add_cia402_tests(Catalogue& c);

// ---- SII as read back ------------------------------------------------------------------------------
struct SiiCategory {
    uint16_t type = 0;
    std::size_t offset = 0;  // byte offset of the data (after the 4-byte header)
    std::size_t length = 0;  // bytes
};

struct SiiImage {
    std::vector<uint8_t> bytes;  // whole EEPROM as read
    std::string error;           // why the category chain could not be walked ("" = fine)
    std::vector<SiiCategory> categories;
    uint16_t word(std::size_t w) const;
    uint32_t dword(std::size_t w) const;
    const SiiCategory* find(uint16_t type) const;
    std::span<const uint8_t> data(const SiiCategory& c) const;
    std::string string(uint8_t index) const;  // STRINGS category entry (1-based), "" if none
    // The category chain walked from word 0x40: fills categories/error.
    void parse();
};

// The first entry of an SII TxPDO/RxPDO category's data whose data type (ETG.2010 PDO entry byte 4) is of a
// fixed size other than its bit length (byte 5), as text; "" when every entry agrees (tests_sii.cpp).
std::string sii_pdo_entry_types(std::span<const uint8_t> category_data);

struct Options {
    std::string iface;
    uint16_t slave = 0;
    std::string esi_path;
    std::string esi_dir;  // without esi_path: the ESI file of this directory whose device matches the SII
    int device = -1;      // -1: the device whose identity matches the slave
    // The module of each slot of a modular device (esi::parse_module_list); empty: each slot's default.
    std::string modules;
    double timeout_scale = 1.0;
    bool verbose = false;
    std::string foe_file;       // a file name the device's FoE server knows (Bootstrap firmware)
    uint32_t foe_password = 0;  // its password
    // What may change the device beyond its configuration: off unless asked for (docs/conformance.md).
    bool allow_fault = false;        // provoke a drive fault (fault reaction: the drive stops, may brake)
    bool allow_motion = false;       // command motion (profile modes with a set-point)
    bool allow_foe_write = false;    // let an FoE write of --foe-file go through (writes the device's flash)
    std::vector<uint8_t> foe_image;  // what that write sends (--foe-image): the device's own firmware
};

// ---- the run context -------------------------------------------------------------------------------
class Context {
  public:
    Context(master::Master& m, const Options& o);
    // Finds the slave, assigns station addresses, reads the SII and the ESI. "" or why the run cannot start.
    std::string setup();

    master::Master& m;
    esc::Link* link = nullptr;  // for raw frames (source MAC, short and malformed frames)
    Options opt;
    uint16_t slave_count = 0;
    uint16_t station = 0;  // configured station address of the slave under test
    master::Address pos;   // by position
    master::Address addr;  // by station address
    uint8_t initial_state = 0;
    std::optional<SiiImage> sii;
    std::string sii_error;
    std::optional<EsiDevice> esi;
    std::string esi_error;  // why there is no ESI expectation
    // A modular device: the mapping objects of its slots' default modules' PDOs (esi holds the device as
    // configured by default: its own PDOs and objects and those of the default modules).
    std::set<uint16_t> module_mapping_objects;
    // The module of each slot of device d of f as the slave is judged: --modules, else what the slave's
    // 0xF050 (Detected Module Ident List) says, else (with a note) each slot's default. Empty without slots.
    std::vector<std::optional<uint32_t>> modules_of(const EsiFile& f, const EsiDevice& d);
    std::optional<std::vector<uint32_t>> detected_modules;  // 0xF050 as read (once)
    std::string detected_modules_error;                     // why 0xF050 could not be read

    // Scaled timeout, cut to what is left of the running test's budget (at least 1 ms): a slave that lies
    // or stops answering makes each wait short once the test has used its budget.
    std::chrono::milliseconds ms(int base) const;
    std::chrono::steady_clock::time_point budget_end{};  // epoch: no budget

    // Skip reasons ("" = applies).
    std::string need_esi() const;
    std::string need_sii() const;
    std::string need_mailbox() const;
    std::string need_coe() const;
    std::string need_foe() const;
    std::string need_dc() const;
    std::string need_sdo_info() const;
    std::string need_complete_access() const;
    std::string need_402() const;
    std::string need_boot() const;
    // The process-data layout: over CoE where the device has it, else from the SII (SyncM and PDO
    // categories), as a master configures a device without mailbox.
    std::string need_pd_layout() const { return need_sii(); }

    bool has_mailbox() const { return need_mailbox().empty(); }
    // ESC configuration 0x0141 bit 0, read at setup (loaded from SII word 0, ConfigData): with device
    // emulation the ESC itself sets AL status to the value written to AL control (ESC datasheet section II,
    // 0x0141 and 0x0130): no state machine that checks or refuses a request, no error indication, no AL
    // status code (simple IO devices without a controller).
    bool device_emulation = false;
    std::string need_state_machine() const {
        return device_emulation ? "device emulation (0x0141 bit 0): the ESC copies AL control to AL status, "
                                  "no state machine refuses a request or sets the error indication"
                                : "";
    }

    // Protocols the slave announces (SII word 0x1C).
    uint16_t protocols() const;
    bool has_coe() const { return protocols() & 0x04; }
    bool has_foe() const { return protocols() & 0x08; }

    // ---- state ----
    master::Result<uint8_t> state();
    // Brings the slave to INIT (acknowledging errors), and clears all SMs and FMMUs.
    master::Error to_init();
    // ESC reset (ESC datasheet section II, 0x0040 "ESC Reset ECAT": 'R', 'E', 'S' written in three
    // consecutive frames), for a slave that cannot be brought back to INIT otherwise. True if the ESC was
    // reset: 0x0010, read by position, no longer holds its station address (the reset clears it). False
    // where the ESC has no reset. The station addresses are assigned again either way.
    bool esc_reset();
    // INIT -> PREOP with the standard mailbox; sets up mbx/sdo. Idempotent when already in PREOP.
    master::Error to_preop();
    // Requests a state, returns the AL status reached (error indication kept, not acknowledged).
    master::AlStatus request_raw(uint8_t state, std::chrono::milliseconds wait);
    master::Error ack_error();
    // A request whose state the slave shows reached with the error indication set (AL status bit 4 beside
    // the requested state): acknowledged; true, and st the status after it, if the slave then shows the state
    // without error. The to_* bring-ups carry on there (noted once per state): the indication belongs to a
    // refused or left state (ETG.1000.6 ESM), and the esm tests, which request states themselves, judge it;
    // without this one lying flag fails every test that needs the state.
    bool reached_despite_error(uint8_t want, master::AlStatus& st);
    uint8_t error_flag_noted = 0;  // the states reached_despite_error has noted (bit mask, AL state values)
    // PREOP -> SAFEOP with the slave's current PDO assignment (layout read over CoE), SMs and FMMUs set
    // up by pds; dc as given. to_op: on to OP while exchanging process data.
    master::Error to_safeop(const master::DcConfig& dc = {});
    master::Error to_op();
    // INIT -> BOOT with the bootstrap mailbox of the SII.
    master::Error to_boot();
    // Reaches a state by valid transitions (1 INIT, 2 PREOP, 3 BOOT, 4 SAFEOP, 8 OP).
    master::Error reach(uint8_t state);
    // Exchanges process data for `cycles` cycles of 1 ms (keeps outputs valid and the watchdog fed).
    master::Error cycle(unsigned cycles = 1);
    // A fresh process-data session for the slave in PREOP with its layout discovered: over CoE (sdo) or,
    // without CoE, from the SII.
    master::Error discover_pd();
    // Sets up SMs/FMMUs for the discovered layout; a device without process data (a coupler) needs none.
    // Without DC asked for, a device that runs only DC-synchronous gets the DC set-up of dc_only().
    master::Error configure_pd(const master::DcConfig& dc = {});
    // A device that supports neither free run nor SM synchronisation (0x1C32:04, else 0x1C33:04, bits 0-1
    // clear, a DC bit set; Beckhoff's EJ/ER servo terminals): the DC set-up of its ESI's op mode, 1 ms cycle.
    // Read once in PREOP; nullopt for every other device.
    std::optional<master::DcConfig> dc_only();
    std::optional<std::optional<master::DcConfig>> dc_only_cache;
    bool has_process_data() const { return pds && pds->layout().sms_with_data() > 0; }
    // SAFEOP -> OP: exchanging process data where there is some (each_cycle before every cycle of the wait: a
    // drive's controlword held), else by AL control alone.
    master::Error request_op(master::AlStatus& st, const std::function<void()>& each_cycle = {});
    // SAFEOP -> OP for a test that needs OP rather than judges the request (to_op, the drive tests, the DC
    // tests): request_op, and a state shown reached with the error indication taken as reached
    // (reached_despite_error).
    master::Error enter_op(master::AlStatus& st, const std::function<void()>& each_cycle = {});
    std::unique_ptr<master::ProcessDataSession> pds;
    // The longest pause of this tool's own process-data cycles since pd_gap_reset() (over every session of
    // the test): a slave whose watchdog or DC synchronisation check saw that pause reacted rightly.
    std::chrono::nanoseconds pd_gap() const;
    void pd_gap_reset();
    void drop_pds();  // ends the process-data session, keeping its longest pause
    std::chrono::nanoseconds pd_gap_dropped{0};
    master::AlStatus last_status;  // of the last refused to_* call
    unsigned al_timeouts = 0;      // requests of this group neither reached nor refused within their wait
    bool al_note = false;

    std::unique_ptr<master::Mailbox> mbx;
    std::unique_ptr<master::SdoClient> sdo;
    // Ends the SDO client (to_init, esc_reset), keeping its last abort and mailbox error for sdo_error().
    void drop_sdo();
    bool dropped = false;
    uint32_t dropped_abort = 0;
    uint16_t dropped_mailbox_error = 0;
    bool in_preop = false;  // set by to_preop, cleared by to_init
    // A segmented transfer a test's own requests (sdo_raw) left open: ended after every test, and by a test
    // before its next request where it only wanted the first answer (end_open_sdo in sdo_util.hpp), so that
    // no transfer starts while another is in progress.
    struct OpenSdo {
        uint16_t index = 0;
        uint8_t sub = 0;
        bool upload = false;
        bool toggle = false;  // of the next segment
    };
    std::optional<OpenSdo> sdo_open;

    // ---- mailbox helpers ----
    // Writes a whole SM0 message (header included, padded to the SM length) as given.
    master::Error mbx_write_raw(std::span<const uint8_t> message);
    // Reads one message from SM1 (header included); Error::MailboxTimeout if none in time.
    master::Error mbx_read_raw(std::vector<uint8_t>& out, std::chrono::milliseconds timeout);
    // After raw traffic: the mailbox client restarts with counter 0 and an empty SM1.
    void mbx_resync();
    // One CoE request through the client's counter, the raw CoE payload of the first non-emergency answer
    // (CoE or mailbox error message: type in mailbox_type).
    master::Error coe_request(std::span<const uint8_t> coe, std::vector<uint8_t>& answer,
                              uint8_t& mailbox_type);

    // SDO helpers with readable errors.
    std::string sdo_error(master::Error e) const;
    master::Result<std::vector<uint8_t>> upload(uint16_t index, uint8_t sub, bool ca = false);
    master::Error download(uint16_t index, uint8_t sub, std::span<const uint8_t> data, bool ca = false);
    master::Result<uint64_t> upload_uint(uint16_t index, uint8_t sub);
    master::Error download_uint(uint16_t index, uint8_t sub, uint64_t value, std::size_t bytes);

    // Register access with the slave's station address.
    template <typename T>
    master::Result<T> rd(uint16_t reg) {
        return m.read_reg<T>(addr, reg);
    }
    template <typename T>
    master::Error wr(uint16_t reg, T v) {
        return m.write_reg<T>(addr, reg, v);
    }

    // Sends a whole Ethernet frame and returns the first EtherCAT frame that comes back whose first datagram
    // carries index `index` (empty if none within the timeout).
    std::vector<uint8_t> raw_exchange(std::span<const uint8_t> frame, uint8_t index,
                                      std::chrono::milliseconds timeout);

    // The restore note ("" if the state found at start was restored).
    std::string restore();
    std::vector<std::string> notes;                      // printed at the end
    std::map<std::string, std::shared_ptr<void>> cache;  // what several tests of a group share
};

std::string hex(uint64_t v, int digits = 4);
std::string bytes_hex(std::span<const uint8_t> b, std::size_t max = 32);
std::string al_code_text(uint16_t code);
std::string state_text(uint8_t s);
// Why the SYNC0 tests cannot run ("" if they can): the ESI lists op modes and none generates SYNC0
// (tests_dc.cpp).
std::string need_sync0_op_mode(const Context& ctx);

}  // namespace conform
