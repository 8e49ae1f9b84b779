#pragma once
// ecatctl firmware-update (the FoE update procedure of the EPOS4 Application Notes §4.2-4.9) and the
// progress bar of FoE transfers (also used by `foe write`).
#include <chrono>
#include <cstddef>
#include <functional>
#include <string>

#include "master/foe.hpp"
#include "master/master.hpp"

namespace CLI {
class App;
}

namespace ecatctl {

// Runs fn with a master on the link the global options name; returns fn's exit code or the link's.
using RunWithMaster = std::function<int(const std::function<int(master::Master&)>&)>;

// Progress of an FoE transfer on stderr: bytes, percent and rate. On a terminal one line redrawn at most
// ten times a second; otherwise (with force) one line per 10 % and one when the slave starts storing.
// Disabled unless stderr is a terminal or force is set.
class ProgressBar {
  public:
    ProgressBar(std::string label, bool force);
    bool enabled() const { return enabled_; }
    void update(const master::FoeProgress& p);
    // Ends the bar's line (a terminal line is left standing with its final figures).
    void finish();
    // A callback for master::FoeClient::set_progress (empty when disabled).
    std::function<void(const master::FoeProgress&)> callback();

  private:
    void draw(const master::FoeProgress& p, bool final);

    std::string label_;
    bool enabled_ = false;
    bool tty_ = false;
    bool drawn_ = false;
    bool storing_said_ = false;
    int last_decile_ = -1;
    std::chrono::steady_clock::time_point start_;
    std::chrono::steady_clock::time_point last_draw_;
    master::FoeProgress last_{};
};

// Registers `firmware-update` on app; its callback sets rc.
void add_firmware_update(CLI::App& app, RunWithMaster run, int& rc);

}  // namespace ecatctl
