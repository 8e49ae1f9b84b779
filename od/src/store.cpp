#include "od/store.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <vector>

#include "util/atomic_file.hpp"
#include "util/crc.hpp"
#include "util/le.hpp"
#include "util/strfmt.hpp"

namespace od {
namespace {

constexpr char kMagic[8] = {'S', 'E', 'C', 'A', 'T', 'P', 'R', 'M'};
constexpr std::size_t kMaxFileBytes = 1u << 20;  // far above any dictionary; bounds what a bad file costs
constexpr std::size_t kRecordHeader = 8;

using util::append16;
using util::append32;
using util::get16;
using util::get32;

void set32(std::vector<uint8_t>& b, std::size_t at, uint32_t v) {
    util::put32(b.data() + at, v);
}

struct Ident {
    uint32_t vendor = 0, product = 0, revision = 0;
};
Ident identity_of(const Dictionary& d) {
    Ident id;
    auto get = [&](uint8_t sub) {
        auto r = d.raw(0x1018, sub);
        return r.size() == 4 ? get32(r, 0) : 0u;
    };
    id.vendor = get(1);
    id.product = get(2);
    id.revision = get(3);
    return id;
}

std::string hex32(uint32_t v) {
    char b[16];
    std::snprintf(b, sizeof b, "0x%08X", v);
    return b;
}

struct Record {
    uint16_t index;
    uint8_t sub;
    std::span<const uint8_t> value;
};

// Validates a whole file image against the dictionary; on success fills `out` and returns "".
std::string parse(std::span<const uint8_t> f, const Dictionary& dict, std::vector<Record>& out) {
    out.clear();
    if (f.size() < ParameterStore::kHeaderBytes)
        return "file too short for the header (" + std::to_string(f.size()) + " bytes)";
    if (std::memcmp(f.data(), kMagic, sizeof kMagic) != 0) return "bad magic: not a parameter file";
    if (util::crc32(f.first(36)) != get32(f, 36)) return "header CRC mismatch";
    if (get16(f, 8) != ParameterStore::kFormatVersion)
        return "unsupported format version " + std::to_string(get16(f, 8));
    if (get16(f, 10) != ParameterStore::kHeaderBytes) return "unexpected header size";
    const uint32_t count = get32(f, 24);
    const uint32_t payload = get32(f, 28);
    if (f.size() != ParameterStore::kHeaderBytes + payload)
        return "file is " + std::to_string(f.size()) + " bytes, header announces " +
               std::to_string(ParameterStore::kHeaderBytes + payload) + " (truncated or extended)";
    const auto body = f.subspan(ParameterStore::kHeaderBytes);
    if (util::crc32(body) != get32(f, 32)) return "payload CRC mismatch";
    const Ident id = identity_of(dict);
    const Ident fid{get32(f, 12), get32(f, 16), get32(f, 20)};
    if (fid.vendor != id.vendor || fid.product != id.product || fid.revision != id.revision)
        return "stored for vendor " + hex32(fid.vendor) + " product " + hex32(fid.product) + " revision " +
               hex32(fid.revision) + ", this device is " + hex32(id.vendor) + "/" + hex32(id.product) + "/" +
               hex32(id.revision);
    // Every record takes at least its 8-byte header: a count the payload cannot hold is refused before
    // anything is reserved for it (a count of 0xFFFFFFFF with valid CRCs must not cost 100 GB).
    if (count > body.size() / kRecordHeader)
        return "header announces " + std::to_string(count) + " records, the " + std::to_string(body.size()) +
               "-byte payload holds at most " + std::to_string(body.size() / kRecordHeader);
    std::size_t at = 0;
    out.reserve(count);
    for (uint32_t n = 0; n < count; ++n) {
        if (body.size() - at < kRecordHeader) return "record " + std::to_string(n) + " truncated";
        Record r{get16(body, at), body[at + 2], {}};
        const auto type = static_cast<DataType>(get16(body, at + 4));
        const uint16_t len = get16(body, at + 6);
        at += kRecordHeader;
        if (body.size() - at < len) return "record " + std::to_string(n) + " truncated";
        r.value = body.subspan(at, len);
        at += len;
        const std::string where = util::strprintf("0x%04X:%02X", r.index, r.sub);
        const Entry* e = dict.find(r.index, r.sub);
        if (!e) return std::string("entry ") + where + " does not exist";
        if (!e->backup()) return std::string("entry ") + where + " is not a stored parameter";
        if (e->type != type) return std::string("entry ") + where + " has another data type";
        if (const Status st = dict.check(r.index, r.sub, r.value); st != Status::Ok)
            return std::string("entry ") + where + ": " + std::string(to_string(st));
        out.push_back(r);
    }
    if (at != body.size()) return "bytes after the last record";
    std::vector<std::pair<uint16_t, uint8_t>> keys;
    keys.reserve(out.size());
    for (const Record& r : out)
        keys.emplace_back(r.index, r.sub);
    std::sort(keys.begin(), keys.end());
    if (std::adjacent_find(keys.begin(), keys.end()) != keys.end()) return "an entry is stored twice";
    return {};
}

std::string errno_text(const std::string& what, const std::filesystem::path& p) {
    return what + " " + p.string() + ": " + std::strerror(errno);
}

// Reads a whole file. Returns false with errno_code = ENOENT if it does not exist.
bool read_file(const std::filesystem::path& p, std::vector<uint8_t>& out, std::string& error, bool& missing) {
    missing = false;
    // O_NONBLOCK: a FIFO in place of the file must not hang the start (it is refused below).
    const int fd = ::open(p.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) {
        missing = errno == ENOENT;
        if (!missing) error = errno_text("cannot open", p);
        return false;
    }
    struct stat st {};
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        error = "not a regular file: " + p.string();
        ::close(fd);
        return false;
    }
    if (static_cast<std::size_t>(st.st_size) > kMaxFileBytes) {
        error = "file too large: " + p.string();
        ::close(fd);
        return false;
    }
    out.resize(static_cast<std::size_t>(st.st_size));
    std::size_t got = 0;
    while (got < out.size()) {
        const ssize_t n = ::read(fd, out.data() + got, out.size() - got);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;
        got += static_cast<std::size_t>(n);
    }
    ::close(fd);
    out.resize(got);
    return true;
}

bool sync_dir(const std::filesystem::path& dir) {
    return util::sync_directory(dir);
}

}  // namespace

bool in_scope(StoreScope scope, uint16_t index) {
    switch (scope) {
        case StoreScope::All:
            return true;
        case StoreScope::Communication:
            return index >= 0x1000 && index <= 0x1FFF;
        case StoreScope::Application:
            return index >= 0x2000;
    }
    return false;
}

ParameterStore::ParameterStore(std::filesystem::path state_dir, std::string file_name)
    : dir_(std::move(state_dir)), file_(dir_ / file_name) {}

ParameterStore::LoadResult ParameterStore::load(Dictionary& dict) const {
    LoadResult r;
    std::vector<uint8_t> bytes;
    bool missing = false;
    if (!read_file(file_, bytes, r.error, missing)) {
        r.found = !missing;
        return r;
    }
    r.found = true;
    std::vector<Record> records;
    r.error = parse(bytes, dict, records);
    if (!r.error.empty()) {
        r.error = file_.string() + ": " + r.error + "; defaults kept";
        return r;
    }
    for (const Record& rec : records)
        dict.set_raw(rec.index, rec.sub, rec.value);  // validated above
    r.applied = true;
    r.entries = records.size();
    return r;
}

namespace {

std::vector<uint8_t> serialize(const Dictionary& dict, const std::vector<Record>& records) {
    std::vector<uint8_t> b(kMagic, kMagic + sizeof kMagic);
    const Ident id = identity_of(dict);
    append16(b, ParameterStore::kFormatVersion);
    append16(b, static_cast<uint16_t>(ParameterStore::kHeaderBytes));
    append32(b, id.vendor);
    append32(b, id.product);
    append32(b, id.revision);
    append32(b, static_cast<uint32_t>(records.size()));
    append32(b, 0);  // payload bytes
    append32(b, 0);  // payload CRC
    append32(b, 0);  // header CRC
    for (const Record& r : records) {
        const Entry* e = dict.find(r.index, r.sub);
        append16(b, r.index);
        b.push_back(r.sub);
        b.push_back(0);
        append16(b, static_cast<uint16_t>(e->type));
        append16(b, static_cast<uint16_t>(r.value.size()));
        b.insert(b.end(), r.value.begin(), r.value.end());
    }
    const auto payload = std::span<const uint8_t>(b).subspan(ParameterStore::kHeaderBytes);
    set32(b, 28, static_cast<uint32_t>(payload.size()));
    set32(b, 32, util::crc32(payload));
    set32(b, 36, util::crc32(std::span<const uint8_t>(b).first(36)));
    return b;
}

}  // namespace

std::string ParameterStore::save(const Dictionary& dict, StoreScope scope) {
    // Entries outside the scope keep what the current file holds (if it is valid).
    std::vector<uint8_t> old_bytes;
    std::vector<Record> old;
    std::string ignored;
    bool missing = false;
    if (scope != StoreScope::All && read_file(file_, old_bytes, ignored, missing))
        if (!parse(old_bytes, dict, old).empty()) old.clear();
    std::vector<Record> records;
    for (const Object& o : dict.objects()) {
        for (const Entry& e : o.entries) {
            if (!e.backup()) continue;
            if (in_scope(scope, o.index)) {
                records.push_back({o.index, e.subindex, dict.raw(o.index, e.subindex)});
            } else {
                auto it = std::find_if(old.begin(), old.end(), [&](const Record& r) {
                    return r.index == o.index && r.sub == e.subindex;
                });
                if (it != old.end()) records.push_back(*it);
            }
        }
    }
    const std::vector<uint8_t> bytes = serialize(dict, records);

    return write_atomic(bytes);
}

bool ParameterStore::remove_stale_temp() const {
    return util::remove_stale_temp(file_);
}

std::string ParameterStore::write_atomic(const std::vector<uint8_t>& bytes) {
    return util::write_file_atomic(file_, bytes, on_step);
}

std::string ParameterStore::restore_defaults(const Dictionary& dict, StoreScope scope) {
    if (scope == StoreScope::All) {
        if (::unlink(file_.c_str()) != 0 && errno != ENOENT) return errno_text("cannot remove", file_);
        if (!sync_dir(dir_) && errno != ENOENT) return errno_text("cannot sync directory", dir_);
        return {};
    }
    // Rewrite the file without the scope's entries (an invalid or missing file: nothing is stored anyway).
    std::vector<uint8_t> bytes;
    std::vector<Record> records;
    std::string error;
    bool missing = false;
    if (!read_file(file_, bytes, error, missing)) return missing ? std::string{} : error;
    if (!parse(bytes, dict, records).empty()) return restore_defaults(dict, StoreScope::All);
    std::vector<Record> keep;
    for (const Record& r : records)
        if (!in_scope(scope, r.index)) keep.push_back(r);
    return write_atomic(serialize(dict, keep));
}

void attach_store(Dictionary& dict, ParameterStore& store, std::function<Status()> restore_allowed,
                  StoreResult on_result) {
    struct Command {
        uint16_t index;
        bool save;
        bool cia;  // CiA 301 object (1010/1011): subindex 1 all, 2 communication, 3 application
    };
    constexpr Command kCommands[] = {
        {0x1010, true, true}, {0x1011, false, true}, {0x2110, true, false}, {0x2111, false, false}};
    for (const Command cmd : kCommands) {
        if (!dict.find(cmd.index)) continue;
        Dictionary* d = &dict;
        ParameterStore* s = &store;
        dict.add_validator(
            cmd.index, [d, s, cmd, restore_allowed, on_result](const Entry& e, std::span<const uint8_t> v) {
                if (e.subindex == 0 || v.size() != 4) return Status::Ok;
                StoreScope scope = StoreScope::All;
                if (e.subindex == 2)
                    scope = StoreScope::Communication;
                else if (e.subindex == (cmd.cia ? 3 : 6))
                    scope = StoreScope::Application;
                else if (e.subindex != 1)
                    return Status::InvalidValue;
                uint32_t sig;
                std::memcpy(&sig, v.data(), 4);
                if (sig != (cmd.save ? kSignatureSave : kSignatureLoad)) return Status::CannotStore;
                if (!cmd.save && restore_allowed)
                    if (const Status st = restore_allowed(); st != Status::Ok) return st;
                const std::string err = cmd.save ? s->save(*d, scope) : s->restore_defaults(*d, scope);
                if (on_result) on_result(e, cmd.save, err);
                if (!cmd.cia) d->ref<uint32_t>(e.index, e.subindex).set(err.empty() ? 0x1u : 0x2u);
                return err.empty() ? Status::Ok : Status::HardwareError;
            });
        // After a command the entry reads as capability (CiA 301) or state "done" (maxon), not the signature.
        dict.add_listener(cmd.index, [d](const Entry& e) {
            if (e.subindex != 0) d->ref<uint32_t>(e.index, e.subindex).set(0x1u);
        });
    }
}

}  // namespace od
