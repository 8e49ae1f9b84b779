// Every legal order of a master's start-up writes brings a device to OP with the exact working counter.
// Masters differ in when and how they set up the process data: SOEM in PREOP after its mapping, TwinCAT on
// the way to SAFEOP, others already in INIT; one block per SyncManager or FMMU, several registers in one
// datagram, byte by byte, or the activation byte written last on its own; the sync type 0x1C32:01 and the PDO
// assignment 0x1C12/0x1C13 before or after the SMs. The ESC datasheet (SyncManager and FMMU registers:
// configuration written while deactivated, the activation taken with it or later) and ETG.1000.6 (ESM: the
// process-data SMs and FMMUs are checked at PREOP -> SAFEOP) allow each of them, so the device must take
// each: the class is every order, not the one the tests' master library happens to use. (Not legal, so not
// tried: the activation byte before the configuration it enables, which the ESC then locks.) The DC devices
// also set SYNC0 up in each way masters do (SOEM, IgH, the start time first), before or after the process
// data and the sync type.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "device/device.hpp"
#include "esc/esc.hpp"
#include "esi/device/product.hpp"
#include "esi/esi_reader.hpp"
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "master/session.hpp"
#include "od/product.hpp"

#include "powered_device.hpp"
#include "support/master_bring_up.hpp"
#include "support/temp_dir.hpp"

using namespace master;

namespace startup_order {
namespace {

const Address kSlave = Address::station(0x1001);

struct Unit : test_device::PoweredDevice {
    std::filesystem::path dir;

    explicit Unit(std::shared_ptr<const od::Product> product)
        : dir(test_support::make_temp_dir("softecat-startup-")) {
        device::DeviceOptions o;
        o.product = std::move(product);
        o.state_dir = dir;
        power_on(o);
    }
    ~Unit() {
        dev.reset();
        std::error_code ec;
        std::filesystem::remove_all(dir, ec);
    }
};

std::shared_ptr<const od::Product> example(const std::string& file, const std::string& spec) {
    std::ifstream in(std::string(SOFTECAT_ESI_EXAMPLES "/") + file, std::ios::binary);
    std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    return std::make_shared<od::Product>(esi::load_product(esi::read_esi_text(xml, file), spec));
}

// How the SM and FMMU registers are written.
enum class Encoding {
    Block,         // one datagram per SM (8 bytes) and per FMMU (16 bytes), activation included
    ActivateLast,  // the same with the activation byte 0, then the activation byte alone
    ByteByByte,    // each register byte in its own datagram, in ascending order (activation last)
    AllInOne,      // every process-data SM in one datagram, every FMMU in one datagram
};
// When the process data is set up.
enum class Phase { Init, PreOp };
// In which order: sync type and assignment first, SMs before FMMUs, in SM order, DC last; or all of it
// reversed.
enum class Order { Forward, Reversed };
// Distributed clocks (ESC datasheet section I, DC; ETG.1020 DC start-up): none, or SYNC0 set up as SOEM does
// (0x0981 cleared, the SYNC0 cycle 0x09A0, the 64-bit start time 0x0990, then 0x0981 = 3), as IgH does
// (SYNC0 and SYNC1 cycles in one 8-byte write, the start time, then AssignActivate as one word at 0x0980), or
// with the start time written before the cycle.
enum class Dc { None, Soem, IghWord, StartFirst };

struct Case {
    const char* file;
    const char* spec;
    Encoding encoding;
    Phase phase;
    Order order;
    Dc dc = Dc::None;
};

void PrintTo(const Case& c, std::ostream* os) {
    *os << c.file << (c.spec[0] ? " " : "") << c.spec;
}

std::string name_of(const testing::TestParamInfo<Case>& info) {
    const Case& c = info.param;
    std::string n = std::string(c.file).substr(0, std::string(c.file).find('.')) + "_" + c.spec;
    for (char& ch : n)
        if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
    static const char* const enc[] = {"Block", "ActivateLast", "ByteByByte", "AllInOne"};
    n += std::string("_") + enc[static_cast<int>(c.encoding)];
    n += c.phase == Phase::Init ? "_InInit" : "_InPreOp";
    n += c.order == Order::Forward ? "_Forward" : "_Reversed";
    static const char* const dc[] = {"", "_DcSoem", "_DcIghWord", "_DcStartFirst"};
    n += dc[static_cast<int>(c.dc)];
    return n;
}

// One register write of the start-up.
struct Write {
    uint16_t address;
    std::vector<uint8_t> bytes;
};

std::vector<uint8_t> sm_register(const ProcessDataSm& sm, bool activate) {
    std::vector<uint8_t> r(8, 0);
    r[0] = static_cast<uint8_t>(sm.start);
    r[1] = static_cast<uint8_t>(sm.start >> 8);
    r[2] = static_cast<uint8_t>(sm.length);
    r[3] = static_cast<uint8_t>(sm.length >> 8);
    r[4] = sm.control;
    r[6] = activate && sm.length ? 0x01 : 0x00;
    return r;
}

// FMMU register (ESC datasheet section II, 0x0600 + 16n): logical start, length, start bit 0, stop bit 7,
// physical start, physical start bit 0, type (1 read, 2 write), activate.
std::vector<uint8_t> fmmu_register(uint32_t logical, const ProcessDataLayout::Fmmu& f, bool activate) {
    std::vector<uint8_t> r(16, 0);
    for (int i = 0; i < 4; ++i)
        r[i] = static_cast<uint8_t>(logical >> (8 * i));
    r[4] = static_cast<uint8_t>(f.length);
    r[5] = static_cast<uint8_t>(f.length >> 8);
    r[6] = 0;
    r[7] = 7;
    r[8] = static_cast<uint8_t>(f.physical);
    r[9] = static_cast<uint8_t>(f.physical >> 8);
    r[10] = 0;
    r[11] = f.outputs ? 0x02 : 0x01;
    r[12] = activate ? 0x01 : 0x00;
    return r;
}

// The writes of one register as the encoding makes them (AllInOne is put together by the caller).
void encode(std::vector<Write>& out, uint16_t address, std::vector<uint8_t> active, std::size_t activate_at,
            Encoding e) {
    switch (e) {
        case Encoding::Block:
        case Encoding::AllInOne:
            out.push_back({address, std::move(active)});
            break;
        case Encoding::ActivateLast: {
            std::vector<uint8_t> off = active;
            off[activate_at] = 0;
            out.push_back({address, off});
            out.push_back({static_cast<uint16_t>(address + activate_at), {active[activate_at]}});
            break;
        }
        case Encoding::ByteByByte:
            for (std::size_t i = 0; i < active.size(); ++i)
                out.push_back({static_cast<uint16_t>(address + i), {active[i]}});
            break;
    }
}

class StartupOrder : public testing::TestWithParam<Case> {
  protected:
    // The device's process-data layout as a master learns it (SII, and the PDO assignment over CoE), from a
    // device of its own.
    static ProcessDataLayout layout_of(std::shared_ptr<const od::Product> product, bool& coe) {
        Unit u(std::move(product));
        test_device::PoweredLink link(u);
        Master m(link, test_support::in_process_master_options());
        ProcessDataLayout layout;
        [&] { ASSERT_NO_FATAL_FAILURE(test_support::one_slave_addressed(m)); }();
        coe = u.dev->has_coe();
        auto has_mailbox = m.sii_has_mailbox(kSlave);
        if (coe && has_mailbox && *has_mailbox) {
            Mailbox mbx(m, kSlave);
            SdoClient sdo(mbx);
            [&] { ASSERT_NO_FATAL_FAILURE(test_support::one_slave_in_preop(m, mbx, kSlave)); }();
            ProcessDataSession pds(m, kSlave, sdo);
            EXPECT_EQ(pds.discover(), Error::Ok);
            layout = pds.layout();
        } else {
            coe = false;
            ProcessDataSession pds(m, std::span<const Address>(&kSlave, 1));
            EXPECT_EQ(pds.discover_sii(0), Error::Ok);
            layout = pds.layout();
        }
        return layout;
    }
};

TEST_P(StartupOrder, ReachesOpWithTheExactWorkingCounter) {
    const Case& c = GetParam();
    const auto product = example(c.file, c.spec);
    bool coe = false;
    const ProcessDataLayout layout = layout_of(product, coe);
    ASSERT_FALSE(HasFailure());
    const uint32_t out_bytes = layout.output_bytes(), in_bytes = layout.input_bytes();
    ASSERT_GT(out_bytes + in_bytes, 0u) << "an example with process data";

    // The process-data registers, in the order and encoding of the case.
    std::vector<Write> pd;
    std::vector<ProcessDataSm> sms = layout.sms;
    auto fmmus = layout.fmmus();
    if (c.order == Order::Reversed) {
        std::reverse(sms.begin(), sms.end());
        std::reverse(fmmus.begin(), fmmus.end());
    }
    std::vector<Write> sm_writes, fmmu_writes;
    if (c.encoding == Encoding::AllInOne) {
        // SMs from the lowest to the highest process-data SM, FMMU0.. in one datagram each (SMs in between
        // that carry nothing written disabled, as a master clearing them does).
        uint8_t first = 0xFF, last = 0;
        for (const auto& sm : layout.sms) {
            first = std::min(first, sm.index);
            last = std::max(last, sm.index);
        }
        std::vector<uint8_t> block(8u * (last - first + 1), 0);
        for (const auto& sm : layout.sms) {
            const auto r = sm_register(sm, true);
            std::copy(r.begin(), r.end(), block.begin() + 8 * (sm.index - first));
        }
        sm_writes.push_back({static_cast<uint16_t>(reg::Sm0 + 8 * first), block});
        std::vector<uint8_t> fblock;
        for (const auto& f : layout.fmmus()) {
            const auto r = fmmu_register(f.outputs ? f.offset : out_bytes + f.offset, f, true);
            fblock.insert(fblock.end(), r.begin(), r.end());
        }
        fmmu_writes.push_back({reg::Fmmu0, fblock});
    } else {
        for (const auto& sm : sms)
            encode(sm_writes, static_cast<uint16_t>(reg::Sm0 + 8 * sm.index), sm_register(sm, true), 6,
                   c.encoding);
        // The FMMUs from FMMU0 in the layout's order, whatever order they are written in.
        const auto ordered = layout.fmmus();
        for (const auto& f : fmmus) {
            std::size_t n = 0;
            while (n < ordered.size() && !(ordered[n].outputs == f.outputs && ordered[n].offset == f.offset))
                ++n;
            encode(fmmu_writes, static_cast<uint16_t>(reg::Fmmu0 + 16 * n),
                   fmmu_register(f.outputs ? f.offset : out_bytes + f.offset, f, true), 12, c.encoding);
        }
    }
    if (c.order == Order::Forward) {
        pd = sm_writes;
        pd.insert(pd.end(), fmmu_writes.begin(), fmmu_writes.end());
    } else {
        pd = fmmu_writes;
        pd.insert(pd.end(), sm_writes.begin(), sm_writes.end());
    }

    Unit u(product);
    test_device::PoweredLink link(u);
    Master m(link, test_support::in_process_master_options());
    ASSERT_NO_FATAL_FAILURE(test_support::one_slave_addressed(m));
    auto write_all = [&](const std::vector<Write>& ws) {
        for (const Write& w : ws)
            ASSERT_EQ(m.write(kSlave, w.address, w.bytes), Error::Ok) << std::hex << "0x" << w.address;
    };
    if (c.phase == Phase::Init) {
        ASSERT_NO_FATAL_FAILURE(write_all(pd));
    }

    Mailbox mbx(m, kSlave);
    SdoClient sdo(mbx);
    AlStatus st;
    auto has_mailbox = m.sii_has_mailbox(kSlave);
    ASSERT_TRUE(static_cast<bool>(has_mailbox));
    if (*has_mailbox) {
        ASSERT_EQ(mbx.configure_from_sii(), Error::Ok);
    }
    ASSERT_EQ(m.request_state(kSlave, AlState::PreOp, &st), Error::Ok) << std::hex << st.code;

    // In PREOP: the sync type (SM-synchronous where the device announces it) and the assignment written back
    // as it is (subindex 0 to 0, the PDOs, subindex 0 to their count: ETG.1000.6 PDO assignment), where the
    // device lets them be written.
    auto coe_writes = [&] {
        if (!coe) return;
        uint8_t sup[2] = {};
        const uint8_t type = c.dc == Dc::None ? 1 : 2;  // SM-synchronous, or DC SYNC0
        if (auto n = sdo.upload(0x1C32, 4, sup);
            n && *n == 2 && (sup[0] & (c.dc == Dc::None ? 0x02 : 0x04))) {
            const uint8_t v[2] = {type, 0};
            EXPECT_EQ(sdo.download(0x1C32, 1, v), Error::Ok);
        }
        for (const bool outputs : {true, false}) {
            const uint16_t index = outputs ? 0x1C12 : 0x1C13;
            const auto pdos = layout.pdos(outputs);
            const uint8_t zero = 0;
            if (sdo.download(index, 0, std::span<const uint8_t>(&zero, 1)) != Error::Ok) continue;  // fixed
            for (std::size_t k = 0; k < pdos.size(); ++k) {
                const uint8_t v[2] = {static_cast<uint8_t>(pdos[k]), static_cast<uint8_t>(pdos[k] >> 8)};
                EXPECT_EQ(sdo.download(index, static_cast<uint8_t>(k + 1), v), Error::Ok);
            }
            const auto count = static_cast<uint8_t>(pdos.size());
            EXPECT_EQ(sdo.download(index, 0, std::span<const uint8_t>(&count, 1)), Error::Ok);
        }
    };
    // SYNC0 every millisecond from 2 ms after the system time read now.
    auto dc_writes = [&] {
        if (c.dc == Dc::None) return;
        auto now = m.read_reg<uint64_t>(kSlave, reg::DcSystemTime);
        ASSERT_TRUE(static_cast<bool>(now));
        const uint64_t start = *now + 2'000'000;
        uint8_t start_bytes[8], cycles[8] = {};
        for (int i = 0; i < 8; ++i)
            start_bytes[i] = static_cast<uint8_t>(start >> (8 * i));
        const uint32_t cycle = 1'000'000;
        for (int i = 0; i < 4; ++i)
            cycles[i] = static_cast<uint8_t>(cycle >> (8 * i));
        switch (c.dc) {
            case Dc::Soem:
                ASSERT_EQ(m.write_reg<uint8_t>(kSlave, 0x0981, 0), Error::Ok);
                ASSERT_EQ(m.write(kSlave, 0x09A0, std::span<const uint8_t>(cycles, 4)), Error::Ok);
                ASSERT_EQ(m.write(kSlave, 0x0990, start_bytes), Error::Ok);
                ASSERT_EQ(m.write_reg<uint8_t>(kSlave, 0x0981, 0x03), Error::Ok);
                break;
            case Dc::IghWord:
                ASSERT_EQ(m.write(kSlave, 0x09A0, cycles), Error::Ok);
                ASSERT_EQ(m.write(kSlave, 0x0990, start_bytes), Error::Ok);
                ASSERT_EQ(m.write_reg<uint16_t>(kSlave, 0x0980, 0x0300), Error::Ok);
                break;
            case Dc::StartFirst:
                ASSERT_EQ(m.write(kSlave, 0x0990, start_bytes), Error::Ok);
                ASSERT_EQ(m.write(kSlave, 0x09A0, std::span<const uint8_t>(cycles, 4)), Error::Ok);
                ASSERT_EQ(m.write_reg<uint16_t>(kSlave, 0x0980, 0x0300), Error::Ok);
                break;
            case Dc::None:
                break;
        }
    };
    if (c.phase == Phase::PreOp) {
        if (c.order == Order::Forward) {
            coe_writes();
            ASSERT_NO_FATAL_FAILURE(write_all(pd));
            ASSERT_NO_FATAL_FAILURE(dc_writes());
        } else {
            ASSERT_NO_FATAL_FAILURE(dc_writes());
            ASSERT_NO_FATAL_FAILURE(write_all(pd));
            coe_writes();
        }
    } else if (c.order == Order::Forward) {
        coe_writes();
        ASSERT_NO_FATAL_FAILURE(dc_writes());
    } else {
        ASSERT_NO_FATAL_FAILURE(dc_writes());
        coe_writes();
    }

    // SAFEOP, then OP while exchanging process data (one LRW: the outputs at 0, the inputs after them).
    std::vector<uint8_t> image(out_bytes + in_bytes, 0);
    const uint16_t expected = static_cast<uint16_t>((out_bytes ? 2 : 0) + (in_bytes ? 1 : 0));
    auto lrw = [&] {
        std::fill(image.begin() + out_bytes, image.end(), 0);
        Datagram d = Datagram::logical(Command::LRW, 0, image);
        EXPECT_EQ(m.exchange(d), Error::Ok);
        return d.wkc;
    };
    ASSERT_EQ(m.request_state(kSlave, AlState::SafeOp, &st), Error::Ok)
        << "AL status code 0x" << std::hex << st.code;
    EXPECT_EQ(lrw(), expected) << "in SAFEOP";
    ASSERT_EQ(m.write_reg<uint16_t>(kSlave, reg::AlControl, 0x08), Error::Ok);
    for (int i = 0; i < 200; ++i) {
        (void)lrw();
        u.idle(1'000'000);
        auto s = m.al_status(kSlave);
        ASSERT_TRUE(static_cast<bool>(s));
        if (s->state == 0x08 || s->error) break;
    }
    auto s = m.al_status(kSlave);
    ASSERT_TRUE(static_cast<bool>(s));
    EXPECT_EQ(s->state, 0x08) << "AL status code 0x" << std::hex << s->code;
    EXPECT_FALSE(s->error) << "AL status code 0x" << std::hex << s->code;
    for (int i = 0; i < 5; ++i)
        EXPECT_EQ(lrw(), expected) << "in OP, cycle " << i;
    if (c.dc != Dc::None) {
        // What runs is DC SYNC0 (0x1C32:01 says what runs, ETG.1020), where the device has the object.
        uint8_t mode[2] = {};
        if (auto n = sdo.upload(0x1C32, 1, mode))
            EXPECT_EQ(mode[0], 2);
        else
            EXPECT_EQ(sdo.last_abort(), 0x06020000u) << "0x1C32 neither read nor absent";
    }
}

std::vector<Case> cases() {
    // A CiA 402 drive (CoE, DC), an analog input terminal with CoE, a digital IO terminal without mailbox, a
    // microcontroller IO device whose ESI is partial.
    const std::pair<const char*, const char*> devices[] = {{"drive402.xml", ""},
                                                           {"analog-in.xml", ""},
                                                           {"digital-io.xml", "0x07d03052:0x00100000"},
                                                           {"mcu-io.xml", "0x00071800:0x00010000"}};
    std::vector<Case> r;
    for (const auto& [file, spec] : devices)
        for (const Encoding e :
             {Encoding::Block, Encoding::ActivateLast, Encoding::ByteByByte, Encoding::AllInOne})
            for (const Phase p : {Phase::Init, Phase::PreOp})
                for (const Order o : {Order::Forward, Order::Reversed})
                    r.push_back({file, spec, e, p, o});
    // The DC devices with SYNC0 set up in each of the ways, in each phase and order.
    for (const char* file : {"drive402.xml", "analog-in.xml"})
        for (const Dc dc : {Dc::Soem, Dc::IghWord, Dc::StartFirst})
            for (const Phase p : {Phase::Init, Phase::PreOp})
                for (const Order o : {Order::Forward, Order::Reversed})
                    r.push_back({file, "", Encoding::Block, p, o, dc});
    return r;
}

INSTANTIATE_TEST_SUITE_P(EveryLegalOrder, StartupOrder, testing::ValuesIn(cases()), name_of);

}  // namespace
}  // namespace startup_order
