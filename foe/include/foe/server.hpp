#pragma once
// FoE server (ETG.1000.6, FoE): firmware download into a FirmwareStore (Bootstrap only) and upload
// of the stored images. An ecat::MailboxHandler for mailbox type FoE: it sees the bytes after the mailbox
// header and answers through the MailboxSender.
//
// Files: "<device>" (e.g. "MAXPOS", the FoE target as the EPOS4 Application Notes §4.8.3 name it for EPOS4)
// and "<device>_<SW>h_<HW>h_<AppNo>h_<AppVer>h.bin" (MAXPOS firmware specification §9.2) are writable in
// Bootstrap; the written image decides its version, the name only selects the firmware. Readable in every
// mailbox state: "<device>" (the active image) and the file name of each stored valid image (active and
// previous slot).
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "ecat/event_sink.hpp"
#include "ecat/mailbox_handler.hpp"
#include "foe/faults.hpp"
#include "foe/sink.hpp"
#include "foe/store.hpp"
#include "foe/wire/foe.hpp"
#include "od/device.hpp"
#include "od/types.hpp"

namespace foe {

struct ServerConfig {
    std::string device_name = "MAXPOS";
    uint32_t password = 0;                    // EPOS4 Application Notes §4.8.3: password 0
    uint64_t timeout_ns = 10'000'000'000ull;  // an idle transfer is dropped after this
    // Largest DATA payload the master sends (SM0 length - 12), per mailbox; a shorter DATA ends the file.
    // 0: take the largest payload the reply mailbox allows (SM1 length - 12).
    std::size_t standard_data_size = 0;
    std::size_t bootstrap_data_size = 0;
    std::size_t max_file_name = 64;
    // Run the commit steps on a worker thread instead of one per poll(): an fsync (10-20 ms on a disk)
    // then never holds up the frame loop. poll() and the repeated DATA only look at its progress.
    bool commit_in_thread = true;
    // The final DATA is answered when the image is stored: ACK once it is active, ERR if storing failed
    // (what SOES and Beckhoff's SSC do; libethercat's FoE client knows no BUSY). Only a commit still
    // running after this long is answered BUSY, well before the shortest mailbox timeout of the masters
    // (ecatctl 1 s, SOEM's firm_update 2 s, IgH 3 s); the master then repeats the DATA
    // (docs/decisions/foe.md). 0: BUSY at once.
    uint64_t busy_after_ns = 500'000'000ull;
    FoeFaults faults;  // testing aid: deliberate deviations (foe/faults.hpp), all off

    // Sizes and device name from the device description.
    static ServerConfig from(const od::DeviceDescription& d);
};

struct ServerStats {
    uint64_t writes_started = 0;
    uint64_t writes_completed = 0;
    uint64_t reads_started = 0;
    uint64_t reads_completed = 0;
    uint64_t errors_sent = 0;
    uint64_t busy_sent = 0;
    uint64_t timeouts = 0;
    uint64_t cancelled = 0;
};

class FoeServer final : public ecat::MailboxHandler {
  public:
    FoeServer(FirmwareSink& store, ServerConfig config = {});
    ~FoeServer() override;
    FoeServer(const FoeServer&) = delete;
    FoeServer& operator=(const FoeServer&) = delete;

    ecat::MailboxType type() const override { return ecat::MailboxType::FoE; }
    bool available(od::AlState state) const override { return state != od::AlState::Init; }
    void handle(std::span<const uint8_t> payload, ecat::MailboxSender& out) override;
    void poll(uint64_t now_ns, ecat::MailboxSender& out) override;
    void on_state_change(od::AlState from, od::AlState to) override;

    // Sets the AL state without a transition (e.g. a server created while the stack is in Bootstrap).
    void set_state(od::AlState state) { state_ = state; }
    // Where the end of each file write (stored, or why not) is reported; null: nowhere.
    void set_event_sink(ecat::EventSink* sink) { events_ = sink; }
    // Ends any transfer (an unfinished download is deleted; a worker commit is stopped after its step).
    void abort_transfer() { cancel(); }
    bool idle() const { return phase_ == Phase::Idle; }
    bool storing() const { return phase_ == Phase::Storing && result_ == Result::Running; }
    const ServerStats& stats() const { return stats_; }

    // The answer to a file name: 0 if well-formed, else why not (decisions in docs/decisions/foe.md).
    static ErrorCode check_name(std::string_view name, std::size_t max_length);

  private:
    enum class Phase : uint8_t { Idle, Writing, Storing, Reading };
    enum class Result : uint8_t { Running, Done, Failed };

    void start_write(uint32_t password, std::string_view name, ecat::MailboxSender& out);
    void start_read(uint32_t password, std::string_view name, ecat::MailboxSender& out);
    void on_data(uint32_t packet, std::span<const uint8_t> data, ecat::MailboxSender& out);
    void on_ack(uint32_t packet, ecat::MailboxSender& out);
    void send_data(ecat::MailboxSender& out);
    void send_ack(uint32_t packet, ecat::MailboxSender& out);
    void send_busy(ecat::MailboxSender& out);
    void send_error(ErrorCode code, std::string_view detail, ecat::MailboxSender& out);
    void cancel();
    void start_commit();
    void reap_commit();
    std::size_t full_data_size(const ecat::MailboxSender& out) const;
    bool writable(std::string_view name) const;
    void report_write(uint32_t code, std::string_view text);  // once per write, if one is open

    FirmwareSink& store_;
    ServerConfig config_;
    od::AlState state_ = od::AlState::Init;
    Phase phase_ = Phase::Idle;
    Result result_ = Result::Running;
    StoreError error_;
    uint64_t now_ns_ = 0;
    uint64_t activity_ns_ = 0;
    // The final DATA waits for its answer until the commit ends or busy_at_ns_ (ServerConfig::busy_after_ns).
    bool answer_pending_ = false;
    uint32_t pending_packet_ = 0;
    uint64_t busy_at_ns_ = 0;
    void answer_pending(ecat::MailboxSender& out);

    // Writing: next expected packet; the largest DATA payload seen this transfer.
    uint32_t packet_ = 0;
    std::size_t seen_data_size_ = 0;

    // Reading.
    int read_fd_ = -1;
    uint64_t read_offset_ = 0;
    uint64_t read_size_ = 0;
    std::size_t last_sent_ = 0;
    bool last_was_final_ = false;

    std::vector<uint8_t> tx_;
    ServerStats stats_;
    ecat::EventSink* events_ = nullptr;
    std::string write_name_;  // the file of the write being reported
    uint64_t write_bytes_ = 0;
    bool write_open_ = false;  // a write request was seen and its end not yet reported

    // Commit on a worker thread (commit_in_thread): 0 running, 1 done, 2 failed.
    std::thread worker_;
    std::atomic<int> worker_result_{0};
    std::atomic<bool> worker_stop_{false};
};

}  // namespace foe
