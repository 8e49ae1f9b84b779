// The fault registry of `ecat-slave --fault` (device/faults.hpp): names, parsing, one flag per fault, and
// faults of every layer reaching the composed drive, seen from the master library in process.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <memory>
#include <set>
#include <sstream>
#include <type_traits>

#include "device/device.hpp"
#include "device/faults.hpp"
#include "esc/clock.hpp"
#include "esc/esc.hpp"
#include "master/coe.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"

#include "powered_device.hpp"
#include "support/master_bring_up.hpp"
#include "support/temp_dir.hpp"
#include "support/wire_link.hpp"

using namespace device;

namespace {

// Every flag struct is made of bools only, so a fault's effect can be counted byte by byte.
template <typename T>
std::vector<std::size_t> set_bytes(const T& v, std::size_t base) {
    static_assert(std::is_trivially_copyable_v<T>);
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    std::vector<std::size_t> at;
    for (std::size_t i = 0; i < sizeof(T); ++i)
        if (b[i] != 0) at.push_back(base + i);
    return at;
}

TEST(FaultRegistry, NamesAreUniqueWellFormedAndDescribed) {
    std::set<std::string_view> names;
    ASSERT_EQ(fault_catalogue().size(), kFaultCount);
    for (std::size_t i = 0; i < kFaultCount; ++i) {
        const FaultInfo& f = fault_catalogue()[i];
        EXPECT_EQ(static_cast<std::size_t>(f.fault), i);
        EXPECT_TRUE(names.insert(f.name).second) << f.name;
        EXPECT_FALSE(f.description.empty()) << f.name;
        EXPECT_FALSE(f.clause.empty()) << f.name;
        for (char c : f.name)
            EXPECT_TRUE((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-') << f.name;
        EXPECT_EQ(find_fault(f.name), f.fault);
        EXPECT_EQ(&fault_info(f.fault), &f);
    }
    EXPECT_FALSE(find_fault("list"));
    EXPECT_FALSE(find_fault(""));
    EXPECT_GE(kFaultCount, 22u);  // the twelve of the issue and at least ten more
}

TEST(FaultRegistry, EachFaultSetsExactlyOneFlagOfItsOwn) {
    std::set<std::size_t> used;
    for (const FaultInfo& f : fault_catalogue()) {
        FaultSet set;
        set.set(static_cast<std::size_t>(f.fault));
        esc::EscFaults e;
        DeviceFaults d;
        apply_faults(set, e, d);
        auto at = set_bytes(e, 0);
        const auto dev = set_bytes(d, 1000);
        at.insert(at.end(), dev.begin(), dev.end());
        ASSERT_EQ(at.size(), 1u) << f.name;
        EXPECT_TRUE(used.insert(at[0]).second) << f.name << " shares its flag";
    }
    // Nothing set: every flag off.
    esc::EscFaults e;
    DeviceFaults d;
    apply_faults({}, e, d);
    EXPECT_TRUE(set_bytes(e, 0).empty());
    EXPECT_TRUE(set_bytes(d, 0).empty());
    // The flags are all the layers have: every one of them belongs to a fault.
    EXPECT_EQ(used.size(), sizeof(esc::EscFaults) + sizeof(DeviceFaults));
}

TEST(FaultRegistry, ListsAreParsed) {
    FaultSet set;
    EXPECT_EQ(add_faults("wkc-aprd", set), std::nullopt);
    EXPECT_EQ(add_faults(" ca-no-padding , quickstop-ignored", set), std::nullopt);
    EXPECT_EQ(set.count(), 3u);
    EXPECT_TRUE(set.test(static_cast<std::size_t>(Fault::CaNoPadding)));
    EXPECT_TRUE(set.test(static_cast<std::size_t>(Fault::QuickStopIgnored)));
    EXPECT_EQ(add_faults("wkc-aprd,nonsense,ca-no-padding", set), std::optional<std::string>("nonsense"));
    EXPECT_EQ(add_faults("", set), std::optional<std::string>(""));
    EXPECT_EQ(add_faults("wkc-aprd,", set), std::optional<std::string>(""));
    EXPECT_EQ(add_faults("list", set), std::optional<std::string>("list"));
    std::ostringstream out;
    print_faults(out);
    EXPECT_NE(out.str().find("wkc-aprd "), std::string::npos);
    EXPECT_NE(out.str().find(fault_info(Fault::ModeDisplayStuck).description), std::string::npos);
}

// ---- The composed drive with faults, from the master library ------------------------------------------

std::filesystem::path faults_temp_dir() {
    return test_support::make_temp_dir("softdrive-faults-");
}

struct FaultyDrive : test_device::PoweredDevice {
    std::filesystem::path dir = faults_temp_dir();
    std::unique_ptr<test_device::PoweredLink> link;
    std::unique_ptr<master::Master> m;
    std::unique_ptr<master::Mailbox> mbx;
    std::unique_ptr<master::SdoClient> sdo;
    const master::Address a = master::Address::station(0x1001);

    explicit FaultyDrive(const FaultSet& faults) {
        esc::EscConfig config;
        DeviceOptions options;
        options.state_dir = dir;
        apply_faults(faults, config.faults, options.faults);
        power_on(options, config);
        link = std::make_unique<test_device::PoweredLink>(*this);
        m = std::make_unique<master::Master>(*link, test_support::in_process_master_options());
        mbx = std::make_unique<master::Mailbox>(*m, a);
        sdo = std::make_unique<master::SdoClient>(*mbx);
    }
    ~FaultyDrive() {
        dev.reset();
        std::error_code ec;
        std::filesystem::remove_all(dir, ec);
    }
    void to_preop() { ASSERT_NO_FATAL_FAILURE(test_support::one_slave_in_preop(*m, *mbx, a)); }
    uint32_t sdo_u32(uint16_t index, uint8_t sub) {
        uint8_t b[4] = {};
        EXPECT_TRUE(sdo->upload(index, sub, b).ok());
        return static_cast<uint32_t>(b[0] | (b[1] << 8) | (b[2] << 16)) | (static_cast<uint32_t>(b[3]) << 24);
    }
};

FaultSet only(Fault f) {
    FaultSet s;
    s.set(static_cast<std::size_t>(f));
    return s;
}

TEST(DeviceFaults, IdentityMismatch) {
    FaultyDrive clean({}), faulty(only(Fault::IdentityMismatch));
    for (FaultyDrive* d : {&clean, &faulty})
        ASSERT_NO_FATAL_FAILURE(d->to_preop());
    const uint32_t sii = clean.m->sii_read_u32(clean.a, master::sii::ProductCode).value();
    EXPECT_EQ(clean.sdo_u32(0x1018, 2), sii);
    EXPECT_EQ(faulty.m->sii_read_u32(faulty.a, master::sii::ProductCode).value(), sii);  // the SII as built
    EXPECT_EQ(faulty.sdo_u32(0x1018, 2), sii + 1);
    EXPECT_EQ(faulty.sdo_u32(0x1018, 1), clean.sdo_u32(0x1018, 1));  // vendor id agrees
    // The ESI of the faulty device still names the SII's product code.
    EXPECT_EQ(make_esi(faulty.dev->options()), make_esi(clean.dev->options()));
}

TEST(DeviceFaults, SiiChecksumThroughTheEsc) {
    FaultyDrive clean({}), faulty(only(Fault::SiiChecksum));
    for (FaultyDrive* d : {&clean, &faulty})
        ASSERT_NO_FATAL_FAILURE(test_support::one_slave_addressed(*d->m));
    const uint16_t right = clean.m->sii_read_word(clean.a, 7).value();
    EXPECT_EQ(faulty.m->sii_read_word(faulty.a, 7).value(), right ^ 0x00FF);
    EXPECT_EQ(faulty.m->sii_read_word(faulty.a, 8).value(), clean.m->sii_read_word(clean.a, 8).value());
    ASSERT_NO_FATAL_FAILURE(faulty.to_preop());  // the device works all the same
}

TEST(DeviceFaults, BootstrapRefusedThroughTheStack) {
    FaultyDrive clean({}), faulty(only(Fault::BootstrapRefused));
    for (FaultyDrive* d : {&clean, &faulty}) {
        ASSERT_NO_FATAL_FAILURE(test_support::one_slave_addressed(*d->m));
        ASSERT_EQ(d->mbx->configure_from_sii(/*bootstrap=*/true), master::Error::Ok);
    }
    master::AlStatus st;
    EXPECT_EQ(clean.m->request_state(clean.a, master::AlState::Boot, &st), master::Error::Ok);
    EXPECT_EQ(faulty.m->request_state(faulty.a, master::AlState::Boot, &st), master::Error::AlRefused);
    EXPECT_EQ(st.code, 0x0013);
    // The SII does announce FoE (word 0x1C bit 3) and a bootstrap mailbox (words 0x14-0x17).
    EXPECT_NE(faulty.m->sii_read_word(faulty.a, 0x1C).value() & 0x0008, 0);
    EXPECT_NE(faulty.m->sii_read_word(faulty.a, 0x15).value(), 0);
}

TEST(DeviceFaults, AbortMissingObjectThroughTheCoeServer) {
    FaultyDrive clean({}), faulty(only(Fault::AbortMissingObject));
    uint8_t b[4];
    for (FaultyDrive* d : {&clean, &faulty}) {
        ASSERT_NO_FATAL_FAILURE(d->to_preop());
        EXPECT_FALSE(d->sdo->upload(0x5FFF, 0, b).ok());
    }
    EXPECT_EQ(clean.sdo->last_abort(), 0x06020000u);
    EXPECT_EQ(faulty.sdo->last_abort(), 0x06090011u);
}

TEST(DeviceFaults, ModeDisplayStuckThroughTheDrive) {
    FaultyDrive clean({}), faulty(only(Fault::ModeDisplayStuck));
    for (FaultyDrive* d : {&clean, &faulty}) {
        ASSERT_NO_FATAL_FAILURE(d->to_preop());
        auto select = [d](uint8_t mode) {
            ASSERT_EQ(d->sdo->download(0x6060, 0, std::span<const uint8_t>(&mode, 1)), master::Error::Ok);
            d->idle(30'000'000);  // the drive runs on its own outside Op
        };
        ASSERT_NO_FATAL_FAILURE(select(8));  // CSP
        EXPECT_EQ(d->sdo_u32(0x6061, 0) & 0xFF, 8u);
        ASSERT_NO_FATAL_FAILURE(select(9));  // CSV
        EXPECT_EQ(d->sdo_u32(0x6061, 0) & 0xFF, d == &clean ? 9u : 8u);
    }
}

}  // namespace
