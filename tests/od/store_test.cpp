// Parameter store: round trip, restore, corrupted and truncated files, foreign identity, crash between the
// temp write and the rename, and the 0x1010/0x1011/0x2110/0x2111 wiring.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include "maxpos/maxpos.hpp"
#include "od/store.hpp"
#include "util/crc.hpp"

using namespace od;
namespace fs = std::filesystem;

namespace {

class StoredParameters : public ::testing::Test {
  protected:
    void SetUp() override {
        char tmpl[] = "/tmp/od-store-XXXXXX";
        ASSERT_NE(::mkdtemp(tmpl), nullptr);
        dir = fs::path(tmpl) / "state";  // not created yet: save() creates it
    }
    void TearDown() override { fs::remove_all(dir.parent_path()); }

    static std::vector<uint8_t> read_all(const fs::path& p) {
        std::ifstream f(p, std::ios::binary);
        return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
    }
    static void write_all(const fs::path& p, const std::vector<uint8_t>& b) {
        std::ofstream f(p, std::ios::binary | std::ios::trunc);
        f.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
    }
    // Changes a few stored parameters away from their defaults.
    static void modify(Dictionary& d) {
        ASSERT_EQ(d.set<uint32_t>(0x6065, 0, 4321), Status::Ok);    // following error window
        ASSERT_EQ(d.set<uint8_t>(0x1600, 0, 2), Status::Ok);        // mapping count
        ASSERT_EQ(d.set<uint16_t>(0x1C12, 1, 0x1603), Status::Ok);  // PDO assignment
        ASSERT_EQ(d.set<int16_t>(0x605E, 0, -1), Status::Ok);       // fault reaction
        ASSERT_EQ(d.set<uint32_t>(0x30A1, 1, 5000), Status::Ok);    // position bandwidth
    }
    static void expect_modified(const Dictionary& d) {
        EXPECT_EQ(d.get<uint32_t>(0x6065, 0), 4321u);
        EXPECT_EQ(d.get<uint8_t>(0x1600, 0), 2);
        EXPECT_EQ(d.get<uint16_t>(0x1C12, 1), 0x1603);
        EXPECT_EQ(d.get<int16_t>(0x605E, 0), -1);
        EXPECT_EQ(d.get<uint32_t>(0x30A1, 1), 5000u);
    }
    static void expect_defaults(const Dictionary& d) {
        EXPECT_EQ(d.get<uint32_t>(0x6065, 0), 2000u);
        EXPECT_EQ(d.get<uint8_t>(0x1600, 0), 8);
        EXPECT_EQ(d.get<uint16_t>(0x1C12, 1), 0x1600);
        EXPECT_EQ(d.get<int16_t>(0x605E, 0), 2);
        EXPECT_EQ(d.get<uint32_t>(0x30A1, 1), 4000u);
    }

    fs::path dir;
    DeviceDescription desc = maxpos::description();
};

}  // namespace

TEST(Crc32, KnownVector) {
    const char* s = "123456789";
    EXPECT_EQ(util::crc32(std::span(reinterpret_cast<const uint8_t*>(s), 9)), 0xCBF43926u);
}

TEST_F(StoredParameters, NoFileKeepsDefaults) {
    Dictionary d = maxpos::dictionary(desc);
    ParameterStore store(dir);
    const auto r = store.load(d);
    EXPECT_FALSE(r.found);
    EXPECT_FALSE(r.applied);
    EXPECT_TRUE(r.error.empty());
    expect_defaults(d);
}

TEST_F(StoredParameters, RoundTripRestoresEveryBackupEntry) {
    Dictionary d = maxpos::dictionary(desc);
    modify(d);
    ASSERT_EQ(d.set<int8_t>(0x6060, 0, 9), Status::Ok);  // not a Backup entry: not stored
    ParameterStore store(dir);
    ASSERT_EQ(store.save(d), "");
    EXPECT_TRUE(fs::exists(store.file()));
    EXPECT_FALSE(fs::exists(fs::path(store.file()).concat(".tmp")));

    Dictionary fresh = maxpos::dictionary(desc);
    const auto r = store.load(fresh);
    EXPECT_TRUE(r.found);
    ASSERT_TRUE(r.applied) << r.error;
    std::size_t backups = 0;
    for (const Object& o : fresh.objects())
        for (const Entry& e : o.entries)
            backups += e.backup();
    EXPECT_EQ(r.entries, backups);
    expect_modified(fresh);
    EXPECT_EQ(fresh.get<int8_t>(0x6060, 0), 8);
}

TEST_F(StoredParameters, RestoreDefaultsDropsTheStoredSet) {
    Dictionary d = maxpos::dictionary(desc);
    modify(d);
    ParameterStore store(dir);
    ASSERT_EQ(store.save(d), "");
    ASSERT_EQ(store.restore_defaults(d), "");
    expect_modified(d);  // running values unchanged (CiA 301: defaults at the next start)
    EXPECT_FALSE(fs::exists(store.file()));
    Dictionary fresh = maxpos::dictionary(desc);
    EXPECT_FALSE(store.load(fresh).found);
    expect_defaults(fresh);
    EXPECT_EQ(store.restore_defaults(d), "");  // nothing stored: still fine
}

TEST_F(StoredParameters, ScopedStoreAndRestore) {
    Dictionary d = maxpos::dictionary(desc);
    modify(d);
    ParameterStore store(dir);
    ASSERT_EQ(store.save(d, StoreScope::Communication), "");  // 0x1600, 0x1C12 only
    Dictionary a = maxpos::dictionary(desc);
    ASSERT_TRUE(store.load(a).applied);
    EXPECT_EQ(a.get<uint8_t>(0x1600, 0), 2);
    EXPECT_EQ(a.get<uint32_t>(0x6065, 0), 2000u);           // application parameters not stored yet
    ASSERT_EQ(store.save(d, StoreScope::Application), "");  // adds them, keeps the communication ones
    Dictionary b = maxpos::dictionary(desc);
    ASSERT_TRUE(store.load(b).applied);
    expect_modified(b);
    ASSERT_EQ(store.restore_defaults(d, StoreScope::Communication), "");
    Dictionary c = maxpos::dictionary(desc);
    ASSERT_TRUE(store.load(c).applied);
    EXPECT_EQ(c.get<uint8_t>(0x1600, 0), 8);
    EXPECT_EQ(c.get<uint32_t>(0x6065, 0), 4321u);
}

TEST_F(StoredParameters, FlippedByteAnywhereKeepsDefaults) {
    Dictionary d = maxpos::dictionary(desc);
    modify(d);
    ParameterStore store(dir);
    ASSERT_EQ(store.save(d), "");
    const std::vector<uint8_t> good = read_all(store.file());
    ASSERT_GT(good.size(), ParameterStore::kHeaderBytes);
    Dictionary fresh = maxpos::dictionary(desc);  // one dictionary: no rejected file may touch it
    for (std::size_t i = 0; i < good.size(); ++i) {
        std::vector<uint8_t> bad = good;
        bad[i] ^= 0x01;
        write_all(store.file(), bad);
        const auto r = store.load(fresh);
        EXPECT_TRUE(r.found);
        EXPECT_FALSE(r.applied) << "flip at byte " << i;
        EXPECT_FALSE(r.error.empty());
        expect_defaults(fresh);
    }
}

TEST_F(StoredParameters, TruncatedAtEveryLengthKeepsDefaults) {
    Dictionary d = maxpos::dictionary(desc);
    modify(d);
    ParameterStore store(dir);
    ASSERT_EQ(store.save(d), "");
    const std::vector<uint8_t> good = read_all(store.file());
    Dictionary fresh = maxpos::dictionary(desc);
    for (std::size_t n = 0; n < good.size(); ++n) {
        write_all(store.file(), std::vector<uint8_t>(good.begin(), good.begin() + static_cast<long>(n)));
        const auto r = store.load(fresh);
        EXPECT_FALSE(r.applied) << "truncated to " << n;
        expect_defaults(fresh);
    }
    std::vector<uint8_t> longer = good;
    longer.push_back(0);
    write_all(store.file(), longer);
    EXPECT_FALSE(store.load(fresh).applied);
    write_all(store.file(), good);
    EXPECT_TRUE(store.load(fresh).applied);
}

TEST_F(StoredParameters, ValidCrcButInvalidContentIsRejectedWhole) {
    // A file that is well-formed but holds an out-of-range value must not apply the entries before it.
    Dictionary d = maxpos::dictionary(desc);
    modify(d);
    ParameterStore store(dir);
    ASSERT_EQ(store.save(d), "");
    std::vector<uint8_t> b = read_all(store.file());
    // find the 0x605A (quick stop option code, only 6 allowed) record and make it 5, then fix the CRCs
    bool patched = false;
    for (std::size_t at = ParameterStore::kHeaderBytes; at + 8 <= b.size();) {
        const uint16_t index = static_cast<uint16_t>(b[at] | (b[at + 1] << 8));
        const uint16_t len = static_cast<uint16_t>(b[at + 6] | (b[at + 7] << 8));
        if (index == 0x605A) {
            b[at + 8] = 5;
            patched = true;
        }
        at += 8 + len;
    }
    ASSERT_TRUE(patched);
    auto put32 = [&](std::size_t at, uint32_t v) {
        for (int i = 0; i < 4; ++i)
            b[at + i] = static_cast<uint8_t>(v >> (8 * i));
    };
    put32(32, util::crc32(std::span<const uint8_t>(b).subspan(ParameterStore::kHeaderBytes)));
    put32(36, util::crc32(std::span<const uint8_t>(b).first(36)));
    write_all(store.file(), b);
    Dictionary fresh = maxpos::dictionary(desc);
    const auto r = store.load(fresh);
    EXPECT_FALSE(r.applied);
    EXPECT_NE(r.error.find("0x605A"), std::string::npos) << r.error;
    expect_defaults(fresh);  // 0x1600, 0x1C12 come before 0x605A in the file and are not applied either
}

TEST_F(StoredParameters, MismatchedIdentityIsRejected) {
    Dictionary d = maxpos::dictionary(desc);
    modify(d);
    ParameterStore store(dir);
    ASSERT_EQ(store.save(d), "");
    for (int which = 0; which < 3; ++which) {
        DeviceDescription other = desc;
        if (which == 0) other.identity.vendor_id = 0x2;
        if (which == 1) other.identity.product_code ^= 1;
        if (which == 2) other.identity.revision += 0x00010000;
        Dictionary o = maxpos::dictionary(other);
        const auto r = store.load(o);
        EXPECT_TRUE(r.found);
        EXPECT_FALSE(r.applied);
        EXPECT_NE(r.error.find("this device is"), std::string::npos) << r.error;
        expect_defaults(o);
    }
    DeviceDescription same_but_serial = desc;  // the serial number is not part of the match
    same_but_serial.identity.serial_number = 77;
    Dictionary s = maxpos::dictionary(same_but_serial);
    EXPECT_TRUE(store.load(s).applied);
}

TEST_F(StoredParameters, CrashBetweenTempWriteAndRenameKeepsTheOldFile) {
    Dictionary d = maxpos::dictionary(desc);
    ParameterStore store(dir);
    ASSERT_EQ(d.set<uint32_t>(0x6065, 0, 1111), Status::Ok);
    ASSERT_EQ(store.save(d), "");
    const std::vector<uint8_t> old_file = read_all(store.file());

    for (const char* crash_at : {"temp-written", "renamed"}) {
        ASSERT_EQ(d.set<uint32_t>(0x6065, 0, 2222), Status::Ok);
        const pid_t pid = ::fork();
        ASSERT_GE(pid, 0);
        if (pid == 0) {
            store.on_step = [crash_at](std::string_view step) {
                if (step == crash_at) ::_exit(42);  // power cut: no destructors, no flush
            };
            store.save(d);
            ::_exit(0);
        }
        int status = 0;
        ASSERT_EQ(::waitpid(pid, &status, 0), pid);
        ASSERT_TRUE(WIFEXITED(status));
        ASSERT_EQ(WEXITSTATUS(status), 42);
        Dictionary fresh = maxpos::dictionary(desc);
        const auto r = store.load(fresh);
        ASSERT_TRUE(r.applied) << r.error;
        if (std::string_view(crash_at) == "temp-written") {
            EXPECT_EQ(read_all(store.file()), old_file);  // the old set, untouched
            EXPECT_EQ(fresh.get<uint32_t>(0x6065, 0), 1111u);
        } else {
            EXPECT_EQ(fresh.get<uint32_t>(0x6065, 0), 2222u);  // the new set, complete
        }
        // a later save over the stale temp file works
        ASSERT_EQ(d.set<uint32_t>(0x6065, 0, 1111), Status::Ok);
        ASSERT_EQ(store.save(d), "");
    }
}

TEST_F(StoredParameters, UnwritableDirectoryReportsAnError) {
    Dictionary d = maxpos::dictionary(desc);
    fs::create_directories(dir.parent_path());
    write_all(dir, {1, 2, 3});  // "state" is a file, not a directory
    ParameterStore store(dir);
    EXPECT_FALSE(store.save(d).empty());
}

TEST_F(StoredParameters, SdoStoreAndRestoreObjects) {
    Dictionary d = maxpos::dictionary(desc);
    ParameterStore store(dir);
    attach_store(d, store);
    modify(d);
    auto le32 = [](uint32_t v) {
        return std::vector<uint8_t>{uint8_t(v), uint8_t(v >> 8), uint8_t(v >> 16), uint8_t(v >> 24)};
    };
    // wrong signature: 0x08000020 and nothing stored
    EXPECT_EQ(d.write(0x1010, 1, AlState::PreOp, le32(0x12345678)), Status::CannotStore);
    EXPECT_EQ(d.write(0x2110, 1, AlState::PreOp, le32(kSignatureLoad)), Status::CannotStore);
    EXPECT_FALSE(fs::exists(store.file()));
    // "save" through CiA 301 0x1010:01, in Op too
    ASSERT_EQ(d.write(0x1010, 1, AlState::Op, le32(kSignatureSave)), Status::Ok);
    EXPECT_TRUE(fs::exists(store.file()));
    EXPECT_EQ(d.get<uint32_t>(0x1010, 1), 1u);  // reads as "saves on command", not the signature
    Dictionary a = maxpos::dictionary(desc);
    ASSERT_TRUE(store.load(a).applied);
    expect_modified(a);
    // "load" through 0x2111:01 only in Pre-Op; the file goes, the running values stay
    EXPECT_EQ(d.write(0x2111, 1, AlState::Op, le32(kSignatureLoad)), Status::WrongState);
    EXPECT_EQ(d.write(0x2111, 1, AlState::PreOp, le32(kSignatureSave)), Status::CannotStore);
    ASSERT_EQ(d.write(0x2111, 1, AlState::PreOp, le32(kSignatureLoad)), Status::Ok);
    EXPECT_EQ(d.get<uint32_t>(0x2111, 1), 1u);  // state: done
    EXPECT_FALSE(fs::exists(store.file()));
    expect_modified(d);
    // maxon store of the axis parameters only (0x2110:06)
    ASSERT_EQ(d.write(0x2110, 6, AlState::SafeOp, le32(kSignatureSave)), Status::Ok);
    Dictionary b = maxpos::dictionary(desc);
    ASSERT_TRUE(store.load(b).applied);
    EXPECT_EQ(b.get<uint32_t>(0x6065, 0), 4321u);
    EXPECT_EQ(b.get<uint8_t>(0x1600, 0), 8);
    // 0x1011:01 "load"
    ASSERT_EQ(d.write(0x1011, 1, AlState::PreOp, le32(kSignatureLoad)), Status::Ok);
    EXPECT_FALSE(fs::exists(store.file()));
    EXPECT_EQ(d.get<uint32_t>(0x1011, 1), 1u);
}

TEST_F(StoredParameters, SdoStoreFailureIsAHardwareErrorAndShowsInTheState) {
    Dictionary d = maxpos::dictionary(desc);
    fs::create_directories(dir.parent_path());
    write_all(dir, {1});  // cannot create the state directory
    ParameterStore store(dir);
    attach_store(d, store);
    const std::vector<uint8_t> save{0x73, 0x61, 0x76, 0x65};  // "save"
    EXPECT_EQ(d.write(0x2110, 1, AlState::PreOp, save), Status::HardwareError);
    EXPECT_EQ(d.get<uint32_t>(0x2110, 1), 2u);  // bit 1: error during store
}

TEST_F(StoredParameters, RestoreWaitsForThePowerDisableCondition) {
    Dictionary d = maxpos::dictionary(desc);
    ParameterStore store(dir);
    bool power_disabled = false;
    attach_store(d, store, [&] { return power_disabled ? Status::Ok : Status::WrongState; });
    ASSERT_EQ(store.save(d), "");
    const std::vector<uint8_t> load{0x6C, 0x6F, 0x61, 0x64};  // "load"
    EXPECT_EQ(d.write(0x2111, 1, AlState::PreOp, load), Status::WrongState);
    EXPECT_TRUE(fs::exists(store.file()));
    power_disabled = true;
    EXPECT_EQ(d.write(0x2111, 1, AlState::PreOp, load), Status::Ok);
    EXPECT_FALSE(fs::exists(store.file()));
}

// Issue 14, finding 3: a 40-byte parameters.bin with valid CRCs, the device's identity and a record count of
// 0xFFFFFFFF threw std::bad_alloc from every start. Crafted headers of every kind are reported and the
// defaults run; nothing is reserved for what the bytes present cannot hold.
TEST_F(StoredParameters, CraftedRecordCountsAreReportedNotReserved) {
    Dictionary d = maxpos::dictionary(desc);
    modify(d);
    ParameterStore store(dir);
    ASSERT_EQ(store.save(d), "");
    const std::vector<uint8_t> good = read_all(store.file());
    auto crafted = [&](uint32_t count, std::size_t payload_bytes) {
        const std::size_t keep = std::min(payload_bytes, good.size() - ParameterStore::kHeaderBytes);
        std::vector<uint8_t> b(
            good.begin(), good.begin() + static_cast<std::ptrdiff_t>(ParameterStore::kHeaderBytes + keep));
        auto put32 = [&](std::size_t at, uint32_t v) {
            for (int i = 0; i < 4; ++i)
                b[at + i] = static_cast<uint8_t>(v >> (8 * i));
        };
        put32(24, count);
        put32(28, static_cast<uint32_t>(b.size() - ParameterStore::kHeaderBytes));
        put32(32, util::crc32(std::span<const uint8_t>(b).subspan(ParameterStore::kHeaderBytes)));
        put32(36, util::crc32(std::span<const uint8_t>(b).first(36)));
        return b;
    };
    // The file as found: 40 bytes, count 0xFFFFFFFF, both CRCs right.
    const auto found = crafted(0xFFFFFFFFu, 0);
    ASSERT_EQ(found.size(), 40u);
    const std::size_t real_count = good[24] | (good[25] << 8);
    for (const auto& [count, payload] : std::vector<std::pair<uint32_t, std::size_t>>{
             {0xFFFFFFFFu, 0},                                         // the reported file
             {0xFFFFFFFFu, good.size()},                               // every record there, count far beyond
             {0x20000000u, 16},                                        // 12 GiB worth of records in 16 bytes
             {static_cast<uint32_t>(real_count + 1), good.size()}}) {  // one more than present
        SCOPED_TRACE("count " + std::to_string(count) + ", payload " + std::to_string(payload));
        write_all(store.file(), crafted(count, payload));
        Dictionary fresh = maxpos::dictionary(desc);
        ParameterStore::LoadResult r;
        ASSERT_NO_THROW(r = store.load(fresh));
        EXPECT_TRUE(r.found);
        EXPECT_FALSE(r.applied);
        EXPECT_FALSE(r.error.empty());
        EXPECT_NE(r.error.find("defaults kept"), std::string::npos) << r.error;
        expect_defaults(fresh);
        // A scoped store reads the current file too: it is ignored, not fatal.
        EXPECT_EQ(store.save(d, StoreScope::Communication), "");
        EXPECT_EQ(store.restore_defaults(d, StoreScope::Application), "");
    }
    write_all(store.file(), found);
    Dictionary fresh = maxpos::dictionary(desc);
    EXPECT_NE(store.load(fresh).error.find("records"), std::string::npos);
}

// Neither a file far beyond any dictionary nor a FIFO in place of parameters.bin stops the start.
TEST_F(StoredParameters, OversizedFileAndFifoAreReported) {
    Dictionary d = maxpos::dictionary(desc);
    ParameterStore store(dir);
    fs::create_directories(dir);
    { std::ofstream f(store.file(), std::ios::binary); }
    fs::resize_file(store.file(), std::uintmax_t{1} << 32);  // sparse 4 GiB
    auto r = store.load(d);
    EXPECT_TRUE(r.found);
    EXPECT_FALSE(r.applied);
    EXPECT_NE(r.error.find("too large"), std::string::npos) << r.error;
    fs::remove(store.file());
    ASSERT_EQ(::mkfifo(store.file().c_str(), 0600), 0);
    r = store.load(d);  // must not block waiting for a writer
    EXPECT_TRUE(r.found);
    EXPECT_FALSE(r.applied);
    EXPECT_FALSE(r.error.empty());
    expect_defaults(d);
}

// Issue 14, finding 7: a save SIGKILLed after its temporary file was written left parameters.bin.tmp behind
// for good. It is removed at the next start (remove_stale_temp), and the file that loads is the old one.
TEST_F(StoredParameters, TemporaryOfASaveKilledHalfWayIsRemovedAtTheStart) {
    Dictionary d = maxpos::dictionary(desc);
    ParameterStore store(dir);
    ASSERT_EQ(d.set<uint32_t>(0x6065, 0, 1111), Status::Ok);
    ASSERT_EQ(store.save(d), "");
    ASSERT_EQ(d.set<uint32_t>(0x6065, 0, 2222), Status::Ok);
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
        store.on_step = [](std::string_view step) {
            if (step == "temp-written") ::kill(::getpid(), SIGKILL);
        };
        store.save(d);
        ::_exit(0);
    }
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << status;
    fs::path tmp = store.file();
    tmp += ".tmp";
    ASSERT_TRUE(fs::exists(tmp));  // what the campaign found

    const ParameterStore at_start(dir);
    EXPECT_TRUE(at_start.remove_stale_temp());
    EXPECT_FALSE(fs::exists(tmp));
    EXPECT_FALSE(at_start.remove_stale_temp());  // nothing left the second time
    Dictionary fresh = maxpos::dictionary(desc);
    ASSERT_TRUE(at_start.load(fresh).applied);
    EXPECT_EQ(fresh.get<uint32_t>(0x6065, 0), 1111u);
}
