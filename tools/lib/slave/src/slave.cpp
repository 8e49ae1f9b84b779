// run_slave(): the ecat-slave program minus its command line. See slave/slave.hpp.
#include "slave/slave.hpp"

#include <net/if.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <optional>
#include <stdexcept>

#include "esc/link.hpp"
#include "esc/link_capture.hpp"
#include "slave/netif.hpp"
#include "slave/runtime.hpp"
#include "util/input_file.hpp"

namespace slave {

std::vector<uint8_t> load_eeprom_file(const SlaveOptions& options) {
    if (options.eeprom_file.empty()) return {};
    // A regular file of at most 128 KiB (the largest SII EEPROM), checked before it is read.
    std::vector<uint8_t> image = util::read_input_bytes(options.eeprom_file, 2 * 65536, "EEPROM image");
    if (image.empty() || image.size() % 2 != 0 || image.size() > 2 * 65536)
        throw std::runtime_error("EEPROM image '" + options.eeprom_file + "' has " +
                                 std::to_string(image.size()) +
                                 " bytes; expected a non-empty, even number of bytes up to 128 KiB");
    return image;
}

namespace {

bool write_file(const std::string& path, std::span<const uint8_t> data) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data.data()), static_cast<std::streamsize>(data.size()));
    return static_cast<bool>(out);
}

// The runtime's, the ESC's and the firmware's figures as "name value" lines.
void write_stats(std::ostream& out, const RuntimeStats& s, const esc::EscStats& e, const Firmware* firmware) {
    out << "runtime.frames_received " << s.frames_received << '\n'
        << "runtime.frames_sent " << s.frames_sent << '\n'
        << "runtime.frames_dropped " << s.frames_dropped << '\n'
        << "runtime.send_errors " << s.send_errors << '\n'
        << "runtime.link_errors " << s.link_errors << '\n'
        << "runtime.wakeups " << s.wakeups << '\n'
        << "runtime.timer_expiries " << s.timer_expiries << '\n'
        << "runtime.frame_ns_mean " << (s.frames_received ? s.frame_ns_total / s.frames_received : 0) << '\n'
        << "runtime.frame_ns_max " << s.frame_ns_max << '\n'
        << "runtime.spin_waits " << s.spin_waits << '\n'
        << "runtime.spin_ns_mean " << (s.spin_waits ? s.spin_ns_total / s.spin_waits : 0) << '\n'
        << "runtime.loop_gaps_over_50us " << s.loop_gaps_over_50us << '\n'
        << "runtime.loop_gaps_over_1ms " << s.loop_gaps_over_1ms << '\n'
        << "runtime.loop_gap_max_ns " << s.loop_gap_max_ns << '\n'
        << "runtime.frames_before_work " << s.frames_before_work << '\n'
        << "esc.frames_processed " << e.frames_processed << '\n'
        << "esc.frames_malformed " << e.frames_malformed << '\n'
        << "esc.frames_ignored " << e.frames_ignored << '\n'
        << "esc.malformed_no_header " << e.malformed_no_header << '\n'
        << "esc.malformed_length " << e.malformed_length << '\n'
        << "esc.malformed_datagram " << e.malformed_datagram << '\n'
        << "esc.datagrams " << e.datagrams << '\n';
    if (s.frames_external != 0 || s.frames_resumed != 0 || s.frames_held != 0 || s.carrier_changes != 0 ||
        s.hold_overflows != 0)
        out << "runtime.frames_external " << s.frames_external << '\n'
            << "runtime.frames_resumed " << s.frames_resumed << '\n'
            << "runtime.frames_held " << s.frames_held << '\n'
            << "runtime.hold_overflows " << s.hold_overflows << '\n'
            << "runtime.out_send_errors " << s.out_send_errors << '\n'
            << "runtime.carrier_changes " << s.carrier_changes << '\n';
    if (firmware != nullptr) firmware->report(out);
}

void print_summary(std::ostream& out, const SlaveOptions& options, const RuntimeStats& s,
                   const esc::EscStats& e, const Firmware* firmware) {
    if (s.frames_received > 0)
        out << "frame processing (received to reply ready): mean " << s.frame_ns_total / s.frames_received
            << " ns, max " << s.frame_ns_max << " ns\n";
    out << "frames received " << s.frames_received << ", sent " << s.frames_sent << ", dropped "
        << s.frames_dropped << ", send errors " << s.send_errors << ", link errors " << s.link_errors
        << ", timer arms " << s.timer_arms << ", expiries " << s.timer_expiries << "; ESC: processed "
        << e.frames_processed << ", ignored " << e.frames_ignored << ", malformed " << e.frames_malformed
        << ", datagrams " << e.datagrams << '\n';
    if (s.spin_waits > 0)
        out << "spin waits " << s.spin_waits << ", mean " << s.spin_ns_total / s.spin_waits << " ns\n";
    if (options.busy_poll || options.spin_us > 0)
        out << "busy loop kept from running: " << s.loop_gaps_over_50us << " times over 50 us, "
            << s.loop_gaps_over_1ms << " over 1 ms, longest " << s.loop_gap_max_ns << " ns\n";
    if (firmware != nullptr) firmware->report(out);
}

// Whether the interface is up with a carrier (IFF_RUNNING: the kernel's operational state, which follows
// the carrier of a NIC and the peer of a veth). Asked through ioctl so it is the caller's network namespace.
bool interface_running(int sock, const std::string& name) {
    ifreq req{};
    if (name.size() >= sizeof req.ifr_name) return false;
    std::memcpy(req.ifr_name, name.c_str(), name.size() + 1);
    if (::ioctl(sock, SIOCGIFFLAGS, &req) != 0) return false;
    return (req.ifr_flags & IFF_UP) != 0 && (req.ifr_flags & IFF_RUNNING) != 0;
}

// The runtime loop, until a signal or a lost link. Returns the exit code.
int run_loop(Runtime& runtime, const std::string& iface, std::ostream& err) {
    set_signal_target(&runtime);
    try {
        runtime.run();
    } catch (...) {
        set_signal_target(nullptr);
        throw;
    }
    set_signal_target(nullptr);
    if (runtime.link_lost()) {
        err << "ecat-slave: network interface '" << iface << "' disappeared\n";
        return kExitFailure;
    }
    return kExitOk;
}

// Segment mode: the devices of options.segment_factory behind the link, the external port on out_iface.
int run_segment(const SlaveOptions& options, esc::Link& link, esc::PcapWriter* capture,
                const std::string& iface, const VethPair* veth, std::ostream& out, std::ostream& err) {
    esc::SystemClock clock;
    std::unique_ptr<esc::Link> out_link;
    if (!options.out_iface.empty()) out_link = esc::open_link(options.out_iface, options.backend);
    RuntimeStats* stats = nullptr;  // the runtime's, once it exists (the send callback counts its errors)
    ExternalSend send;
    if (out_link)
        send = [&out_link, &stats](std::span<const uint8_t> frame) {
            if (!out_link->send(frame) && stats != nullptr) ++stats->out_send_errors;
        };
    std::unique_ptr<SegmentFirmware> segment = options.segment_factory(clock, options, send);
    Runtime runtime(link, segment->segment(), clock, out_link.get());
    stats = &runtime.stats();
    runtime.set_firmware(segment.get());
    runtime.set_capture(capture);
    runtime.set_spin(uint64_t{options.spin_us} * 1000u);
    runtime.set_busy_poll(options.busy_poll);
    runtime.set_link_check([&iface] { return interface_exists(iface); });
    int sock = -1;
    if (out_link) {
        sock = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
        if (sock < 0) sock = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
        const std::string name = options.out_iface;
        runtime.set_carrier_check([sock, name] { return interface_running(sock, name); }, options.log, name);
    }
    if (veth) out << "master interface: " << veth->master_end() << '\n';
    out << "ecat-slave: running " << segment->segment().size() << " devices on " << link.describe()
        << (out_link ? ", external port on " + out_link->describe() : std::string())
        << (capture ? ", capturing to " + options.capture_file : std::string()) << '\n';
    out.flush();
    int code = kExitOk;
    try {
        code = run_loop(runtime, iface, err);
    } catch (...) {
        if (sock >= 0) ::close(sock);
        throw;
    }
    if (sock >= 0) ::close(sock);
    if (capture != nullptr) capture->flush();
    if (code != kExitOk) return code;
    const esc::EscStats e = segment->segment().esc(0).stats();
    if (options.verbose) print_summary(out, options, runtime.stats(), e, segment.get());
    if (!options.stats_file.empty()) {
        std::ofstream file(options.stats_file, std::ios::trunc);
        write_stats(file, runtime.stats(), e, segment.get());
        if (!file.flush()) err << "ecat-slave: warning: could not write " << options.stats_file << '\n';
    }
    out << "ecat-slave: stopped\n";
    return kExitOk;
}

// Real-time setup. Returns an error message, empty on success.
std::string apply_scheduling(const SlaveOptions& options) {
    if (options.cpu >= CPU_SETSIZE) return "CPU " + std::to_string(options.cpu) + " does not exist";
    if (options.cpu >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET(options.cpu, &set);
        if (::sched_setaffinity(0, sizeof set, &set) != 0)
            return "cannot pin to CPU " + std::to_string(options.cpu) + ": " + std::strerror(errno);
    }
    if (options.rt_priority > 0) {
        sched_param param{};
        param.sched_priority = options.rt_priority;
        if (::sched_setscheduler(0, SCHED_FIFO, &param) != 0)
            return "cannot switch to SCHED_FIFO priority " + std::to_string(options.rt_priority) + ": " +
                   std::strerror(errno) + (errno == EPERM ? " (needs CAP_SYS_NICE or root)" : "");
        if (::mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
            return std::string("cannot lock memory (mlockall): ") + std::strerror(errno);
    }
    return {};
}

}  // namespace

int run_slave(const SlaveOptions& options, std::ostream& out, std::ostream& err) {
    if (options.ram_kib == 0 || options.ram_kib > 60) {
        err << "ecat-slave: --ram-kib must be 1..60 (process RAM lies between 0x1000 and 0xFFFF)\n";
        return kExitUsage;
    }
    if (const std::string problem = apply_scheduling(options); !problem.empty()) {
        err << "ecat-slave: " << problem << '\n';
        return kExitUsage;
    }
    install_stop_signals();
    try {
        std::vector<uint8_t> image = options.eeprom_loader && !options.segment_factory
                                         ? options.eeprom_loader(options)
                                         : std::vector<uint8_t>{};

        std::optional<VethPair> veth;
        std::string iface = options.iface;
        if (iface.empty()) {
            const std::string peer =
                options.veth_peer.empty() ? veth_peer_name(options.veth_name) : options.veth_peer;
            veth.emplace(options.veth_name, peer);
            iface = veth->slave_end();
        }
        auto link = esc::open_link(iface, options.backend);
        std::unique_ptr<esc::PcapWriter> capture;
        if (!options.capture_file.empty()) capture = std::make_unique<esc::PcapWriter>(options.capture_file);
        if (options.segment_factory)
            return run_segment(options, *link, capture.get(), iface, veth ? &*veth : nullptr, out, err);

        esc::EscConfig config;
        config.process_ram_kib = options.ram_kib;
        config.port_descriptor = options.port_descriptor;
        config.faults = options.esc_faults;
        config.thread_safe = false;  // the runtime below is the only thread that calls it
        esc::SystemClock clock;
        esc::Esc esc(config, clock);
        bool eeprom_dirty = false;
        if (!image.empty()) {
            esc.load_eeprom(image);
            esc.on_eeprom_write([&eeprom_dirty](uint16_t, uint16_t) { eeprom_dirty = true; });
        } else {
            err << "ecat-slave: warning: no EEPROM image (--eeprom); masters will not identify this slave\n";
        }
        std::unique_ptr<Firmware> firmware;
        if (options.firmware_factory) firmware = options.firmware_factory(esc, options);

        Runtime runtime(*link, esc, clock);
        runtime.set_firmware(firmware.get());
        runtime.set_capture(capture.get());
        runtime.set_spin(uint64_t{options.spin_us} * 1000u);
        runtime.set_busy_poll(options.busy_poll);
        runtime.set_link_check([&iface] { return interface_exists(iface); });

        if (veth) out << "master interface: " << veth->master_end() << '\n';
        out << "ecat-slave: running on " << link->describe()
            << (capture ? ", capturing to " + options.capture_file : "") << '\n';
        out.flush();

        const int code = run_loop(runtime, iface, err);
        if (capture) capture->flush();
        if (code != kExitOk) return code;
        if (eeprom_dirty && options.eeprom_write_back && !options.eeprom_file.empty()) {
            if (!write_file(options.eeprom_file, esc.eeprom()))
                err << "ecat-slave: warning: could not write the EEPROM image back to " << options.eeprom_file
                    << '\n';
        }
        if (options.verbose) print_summary(out, options, runtime.stats(), esc.stats(), firmware.get());
        if (!options.stats_file.empty()) {
            std::ofstream stats(options.stats_file, std::ios::trunc);
            write_stats(stats, runtime.stats(), esc.stats(), firmware.get());
            if (!stats.flush()) err << "ecat-slave: warning: could not write " << options.stats_file << '\n';
        }
        out << "ecat-slave: stopped\n";
        return kExitOk;
    } catch (const esc::LinkError& e) {
        err << "ecat-slave: " << e.what() << '\n';
        return e.kind() == esc::LinkError::Kind::System ? kExitFailure : kExitUsage;
    } catch (const std::exception& e) {
        err << "ecat-slave: " << e.what() << '\n';
        return kExitFailure;
    }
}

}  // namespace slave
