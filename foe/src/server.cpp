#include "foe/server.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <system_error>

#include "util/le.hpp"

namespace foe {
namespace {
using util::get32;
using util::put32;

constexpr std::size_t kFoeHeader = kFoeHeaderSize;  // foe/wire/foe.hpp

char lower(char c) {
    return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
}

bool iequal(std::string_view a, std::string_view b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
        if (lower(a[i]) != lower(b[i])) return false;
    return true;
}

bool is_hex(char c) {
    return (c >= '0' && c <= '9') || (lower(c) >= 'a' && lower(c) <= 'f');
}

// "<device>_XXXXh_XXXXh_XXXXh_XXXXh.bin" (case-insensitive).
bool is_firmware_file_name(std::string_view name, std::string_view device) {
    if (name.size() != device.size() + 4 * 6 + 4) return false;
    if (!iequal(name.substr(0, device.size()), device)) return false;
    std::string_view rest = name.substr(device.size());
    for (int group = 0; group < 4; ++group) {
        if (rest[0] != '_') return false;
        for (int i = 1; i <= 4; ++i)
            if (!is_hex(rest[static_cast<std::size_t>(i)])) return false;
        if (lower(rest[5]) != 'h') return false;
        rest = rest.substr(6);
    }
    return iequal(rest, ".bin");
}

// Name as sent: trailing NUL padding (a C string terminator) is not part of it.
std::string_view name_of(std::span<const uint8_t> bytes) {
    std::size_t n = bytes.size();
    while (n > 0 && bytes[n - 1] == 0)
        --n;
    return {reinterpret_cast<const char*>(bytes.data()), n};
}

}  // namespace

ServerConfig ServerConfig::from(const od::DeviceDescription& d) {
    ServerConfig c;
    c.device_name = d.identity.device_name.empty() ? "MAXPOS" : d.identity.device_name;
    auto data = [](uint16_t sm0) -> std::size_t { return sm0 > 12 ? sm0 - 12u : 0; };
    c.standard_data_size = data(d.standard_mailbox.out_size);
    c.bootstrap_data_size = data(d.bootstrap_mailbox.out_size);
    return c;
}

FoeServer::FoeServer(FirmwareSink& store, ServerConfig config) : store_(store), config_(std::move(config)) {
    tx_.resize(2048);
}

FoeServer::~FoeServer() {
    cancel();
}

ErrorCode FoeServer::check_name(std::string_view name, std::size_t max_length) {
    if (name.empty()) return ErrorCode::NotFound;
    if (name.size() > max_length) return ErrorCode::AccessDenied;
    for (char c : name) {
        const auto u = static_cast<unsigned char>(c);
        if (u < 0x20 || u >= 0x7F || c == '/' || c == '\\' || c == ':') return ErrorCode::AccessDenied;
    }
    if (name.find("..") != std::string_view::npos) return ErrorCode::AccessDenied;
    return ErrorCode::NotDefined;  // well-formed
}

bool FoeServer::writable(std::string_view name) const {
    return iequal(name, config_.device_name) || is_firmware_file_name(name, config_.device_name);
}

std::size_t FoeServer::full_data_size(const ecat::MailboxSender& out) const {
    std::size_t configured =
        state_ == od::AlState::Boot ? config_.bootstrap_data_size : config_.standard_data_size;
    if (configured == 0) configured = out.max_payload() > kFoeHeader ? out.max_payload() - kFoeHeader : 0;
    return std::max(configured, seen_data_size_);
}

void FoeServer::handle(std::span<const uint8_t> payload, ecat::MailboxSender& out) {
    activity_ns_ = now_ns_;
    if (payload.size() < kFoeHeader) {
        cancel();
        send_error(ErrorCode::Illegal, "packet shorter than the FoE header", out);
        return;
    }
    const uint8_t opcode = payload[0];
    const uint32_t value = get32(payload.data() + 2);
    const auto rest = payload.subspan(kFoeHeader);
    switch (static_cast<Opcode>(opcode)) {
        case Opcode::Read:
        case Opcode::Write: {
            if (phase_ != Phase::Idle) ++stats_.cancelled;
            cancel();  // a new request ends whatever transfer was running
            const std::string_view name = name_of(rest);
            if (const ErrorCode e = check_name(name, config_.max_file_name); e != ErrorCode::NotDefined) {
                send_error(e, "file name not allowed", out);
                return;
            }
            if (static_cast<Opcode>(opcode) == Opcode::Write)
                start_write(value, name, out);
            else
                start_read(value, name, out);
            return;
        }
        case Opcode::Data:
            on_data(value, rest, out);
            return;
        case Opcode::Ack:
            on_ack(value, out);
            return;
        case Opcode::Error:
            cancel();  // the master aborts: no answer
            return;
        case Opcode::Busy:
            break;
    }
    cancel();
    send_error(ErrorCode::Illegal, "unexpected opcode", out);
}

void FoeServer::start_write(uint32_t password, std::string_view name, ecat::MailboxSender& out) {
    report_write(static_cast<uint32_t>(ErrorCode::NotDefined), "superseded by a new write request");
    write_name_.assign(name);
    write_bytes_ = 0;
    write_open_ = true;
    if (state_ != od::AlState::Boot) {
        send_error(ErrorCode::BootstrapOnly, "firmware download needs the Bootstrap state", out);
        return;
    }
    if (password != config_.password && !config_.faults.password_ignored) {
        send_error(ErrorCode::NoRights, "wrong password", out);
        return;
    }
    if (!writable(name) && !config_.faults.any_file_name) {
        send_error(ErrorCode::NotFound, "no such file to write", out);
        return;
    }
    StoreError e;
    if (!store_.begin_write(e)) {
        send_error(e.code, e.text, out);
        return;
    }
    ++stats_.writes_started;
    phase_ = Phase::Writing;
    packet_ = 1;
    seen_data_size_ = 0;
    send_ack(0, out);
}

void FoeServer::start_read(uint32_t password, std::string_view name, ecat::MailboxSender& out) {
    if (password != config_.password) {
        send_error(ErrorCode::NoRights, "wrong password", out);
        return;
    }
    const StoredImage* active = store_.active_image() ? &*store_.active_image() : nullptr;
    const StoredImage* image = active && iequal(name, config_.device_name) ? active : nullptr;
    for (const StoredImage* candidate : {active, store_.image(0) ? &*store_.image(0) : nullptr,
                                         store_.image(1) ? &*store_.image(1) : nullptr}) {
        if (!image && candidate && iequal(name, candidate->file_name)) image = candidate;
    }
    if (!image) {
        send_error(ErrorCode::NotFound, store_.active_image() ? "no such file" : "no firmware image stored",
                   out);
        return;
    }
    read_fd_ = store_.open_image(*image);
    if (read_fd_ < 0) {
        send_error(ErrorCode::FlashError, std::strerror(-read_fd_), out);
        read_fd_ = -1;
        return;
    }
    const std::size_t chunk = out.max_payload() > kFoeHeader ? out.max_payload() - kFoeHeader : 0;
    if (chunk == 0) {
        cancel();
        send_error(ErrorCode::ProgramError, "mailbox too small", out);
        return;
    }
    if (tx_.size() < kFoeHeader + chunk) tx_.resize(kFoeHeader + chunk);  // once per mailbox size
    ++stats_.reads_started;
    phase_ = Phase::Reading;
    read_offset_ = 0;
    read_size_ = image->size;
    packet_ = 0;
    send_data(out);
}

void FoeServer::send_data(ecat::MailboxSender& out) {
    const std::size_t chunk = std::min(out.max_payload() - kFoeHeader, tx_.size() - kFoeHeader);
    const std::size_t n = static_cast<std::size_t>(std::min<uint64_t>(chunk, read_size_ - read_offset_));
    std::size_t got = 0;
    while (got < n) {
        const long r =
            store_.read_image(read_fd_, read_offset_ + got, {tx_.data() + kFoeHeader + got, n - got});
        if (r <= 0) {
            cancel();
            send_error(ErrorCode::FlashError, "image file cannot be read", out);
            return;
        }
        got += static_cast<std::size_t>(r);
    }
    ++packet_;
    tx_[0] = static_cast<uint8_t>(Opcode::Data);
    tx_[1] = 0;
    put32(tx_.data() + 2, packet_);
    read_offset_ += n;
    last_sent_ = n;
    last_was_final_ = n < chunk;  // a full last packet is followed by an empty one
    out.send(ecat::MailboxType::FoE, {tx_.data(), kFoeHeader + n});
}

void FoeServer::on_ack(uint32_t packet, ecat::MailboxSender& out) {
    if (phase_ != Phase::Reading) {
        cancel();
        send_error(ErrorCode::Illegal, "ACK without a read", out);
        return;
    }
    if (packet != packet_) {
        cancel();
        send_error(ErrorCode::PacketNumberWrong, "ACK for another packet", out);
        return;
    }
    if (last_was_final_) {
        ++stats_.reads_completed;
        cancel();
        return;
    }
    send_data(out);
}

void FoeServer::on_data(uint32_t packet, std::span<const uint8_t> data, ecat::MailboxSender& out) {
    reap_commit();
    if (phase_ == Phase::Storing && packet == packet_) {
        // The master repeats the last DATA after BUSY (or gave up waiting for its answer): answer with the
        // state of the commit; the pending answer is this one.
        answer_pending_ = false;
        if (result_ == Result::Running) {
            send_busy(out);
        } else if (result_ == Result::Done) {
            phase_ = Phase::Idle;
            send_ack(packet, out);
        } else {
            phase_ = Phase::Idle;
            send_error(error_.code, error_.text, out);
        }
        return;
    }
    if (phase_ != Phase::Writing) {
        cancel();
        send_error(ErrorCode::Illegal, "DATA without a write", out);
        return;
    }
    if (packet + 1 == packet_ && packet != 0) {
        send_ack(packet, out);  // a repeated packet (its ACK was lost): already stored
        return;
    }
    if (packet != packet_) {
        cancel();
        send_error(ErrorCode::PacketNumberWrong, "expected another packet number", out);
        return;
    }
    const std::size_t full = full_data_size(out);
    seen_data_size_ = std::max(seen_data_size_, data.size());
    StoreError e;
    if (!store_.append(data, e)) {
        phase_ = Phase::Idle;
        send_error(e.code, e.text, out);
        return;
    }
    write_bytes_ += data.size();
    if (data.size() >= full) {
        ++packet_;
        send_ack(packet, out);
        return;
    }
    // End of file.
    if (!store_.finish(e)) {
        phase_ = Phase::Idle;
        send_error(e.code, e.text, out);
        return;
    }
    phase_ = Phase::Storing;
    result_ = Result::Running;
    start_commit();
    if (config_.busy_after_ns == 0) {
        send_busy(out);
        return;
    }
    // Answered by poll() when the commit ends (ACK only once the image is active), or BUSY at busy_at_ns_.
    answer_pending_ = true;
    pending_packet_ = packet;
    busy_at_ns_ = now_ns_ + config_.busy_after_ns;
}

void FoeServer::answer_pending(ecat::MailboxSender& out) {
    if (!answer_pending_ || phase_ != Phase::Storing) return;
    if (result_ == Result::Done) {
        answer_pending_ = false;
        phase_ = Phase::Idle;
        send_ack(pending_packet_, out);
    } else if (result_ == Result::Failed) {
        answer_pending_ = false;
        phase_ = Phase::Idle;
        send_error(error_.code, error_.text, out);
    } else if (now_ns_ >= busy_at_ns_) {
        answer_pending_ = false;
        send_busy(out);
    }
}

void FoeServer::start_commit() {
    if (!config_.commit_in_thread) return;
    worker_result_.store(0);
    worker_stop_.store(false);
    try {
        worker_ = std::thread([this] {
            StoreError e;
            FirmwareSink::Progress p = FirmwareSink::Progress::Running;
            while (p == FirmwareSink::Progress::Running && !worker_stop_.load())
                p = store_.commit_step(e);
            if (p == FirmwareSink::Progress::Running) return;  // stopped: cancel() aborts after the join
            error_ = std::move(e);
            worker_result_.store(p == FirmwareSink::Progress::Done ? 1 : 2);
        });
    } catch (const std::system_error&) {
        // No thread to be had: the commit runs one step per poll() instead.
    }
}

// Takes the worker's result once it has finished (the worker wrote error_ before its result).
void FoeServer::reap_commit() {
    if (!worker_.joinable() || worker_result_.load() == 0) return;
    worker_.join();
    if (worker_result_.load() == 1) {
        result_ = Result::Done;
        ++stats_.writes_completed;
        report_write(0, {});
    } else {
        result_ = Result::Failed;
        report_write(static_cast<uint32_t>(error_.code), error_.text);
    }
}

void FoeServer::report_write(uint32_t code, std::string_view text) {
    if (!write_open_) return;
    write_open_ = false;
    if (events_ != nullptr) events_->foe_write(write_name_, write_bytes_, code, text);
}

void FoeServer::poll(uint64_t now_ns, ecat::MailboxSender& out) {
    now_ns_ = now_ns;
    reap_commit();
    if (phase_ == Phase::Storing && result_ == Result::Running) {
        activity_ns_ = now_ns;
        if (!worker_.joinable()) {
            const auto p = store_.commit_step(error_);
            if (p == FirmwareSink::Progress::Done) {
                result_ = Result::Done;
                ++stats_.writes_completed;
                report_write(0, {});
            } else if (p == FirmwareSink::Progress::Failed) {
                result_ = Result::Failed;
                report_write(static_cast<uint32_t>(error_.code), error_.text);
            }
        }
        answer_pending(out);
        return;
    }
    if (answer_pending_) {
        answer_pending(out);
        return;
    }
    if (phase_ != Phase::Idle && now_ns - activity_ns_ > config_.timeout_ns) {
        ++stats_.timeouts;
        if (phase_ == Phase::Writing) report_write(static_cast<uint32_t>(ErrorCode::NotDefined), "timed out");
        cancel();
    }
}

void FoeServer::on_state_change(od::AlState /*from*/, od::AlState to) {
    state_ = to;
    if ((phase_ == Phase::Writing || (phase_ == Phase::Storing && result_ == Result::Running)) &&
        to != od::AlState::Boot)
        report_write(static_cast<uint32_t>(ErrorCode::NotDefined), "abandoned: the slave left Bootstrap");
    // A download belongs to Bootstrap; nothing survives the mailbox being stopped.
    if ((phase_ == Phase::Writing || phase_ == Phase::Storing) && to != od::AlState::Boot) cancel();
    if (to == od::AlState::Init) cancel();
}

void FoeServer::cancel() {
    if (worker_.joinable()) {
        worker_stop_.store(true);
        worker_.join();  // at most one storage step
        if (worker_result_.load() == 1) ++stats_.writes_completed;
        if (worker_result_.load() != 0) result_ = worker_result_.load() == 1 ? Result::Done : Result::Failed;
    }
    if (phase_ == Phase::Writing || (phase_ == Phase::Storing && result_ == Result::Running)) store_.abort();
    answer_pending_ = false;
    if (read_fd_ >= 0) {
        store_.close_image(read_fd_);
        read_fd_ = -1;
    }
    phase_ = Phase::Idle;
}

void FoeServer::send_ack(uint32_t packet, ecat::MailboxSender& out) {
    uint8_t m[kFoeHeader] = {static_cast<uint8_t>(Opcode::Ack), 0};
    put32(m + 2, packet);
    out.send(ecat::MailboxType::FoE, m);
}

void FoeServer::send_busy(ecat::MailboxSender& out) {
    uint8_t m[kFoeHeader] = {static_cast<uint8_t>(Opcode::Busy), 0};
    const uint16_t done = store_.progress_done(), entire = store_.progress_entire();
    m[2] = static_cast<uint8_t>(done);
    m[3] = static_cast<uint8_t>(done >> 8);
    m[4] = static_cast<uint8_t>(entire);
    m[5] = static_cast<uint8_t>(entire >> 8);
    ++stats_.busy_sent;
    out.send(ecat::MailboxType::FoE, m);
}

void FoeServer::send_error(ErrorCode code, std::string_view detail, ecat::MailboxSender& out) {
    ++stats_.errors_sent;
    report_write(static_cast<uint32_t>(code), detail);
    const std::size_t room = out.max_payload() > kFoeHeader ? out.max_payload() - kFoeHeader : 0;
    uint8_t* m = tx_.data();
    m[0] = static_cast<uint8_t>(Opcode::Error);
    m[1] = 0;
    put32(m + 2, static_cast<uint32_t>(code));
    std::size_t n = 0;
    auto add = [&](std::string_view s) {
        const std::size_t k = std::min({s.size(), room - n, tx_.size() - kFoeHeader - n});
        std::memcpy(m + kFoeHeader + n, s.data(), k);
        n += k;
    };
    add(error_text(code));
    if (!detail.empty()) {
        add(": ");
        add(detail);
    }
    out.send(ecat::MailboxType::FoE, {m, kFoeHeader + n});
}

}  // namespace foe
