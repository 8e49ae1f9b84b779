#pragma once
// drive-sim's plot: the samples of a run, the events found in them (homing done, faults and their reset,
// warnings, limit and home switches), and the gnuplot script that draws them: position, velocity, current
// and following error on one time axis (demand drawn wide and light under the actual value), a strip for the
// mode of operation and one for the CiA 402 state from the statusword, every event a dashed line across all
// panels with its name on top, the script's name in the title.
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace drivesim {

struct Sample {
    double t_ms = 0;
    double setpoint = 0;
    int32_t demand = 0, actual = 0, velocity = 0, velocity_demand = 0, following_error = 0;
    int16_t current = 0;
    uint16_t statusword = 0;
    int8_t mode = 0;
    uint32_t inputs = 0;      // 0x60FD: bit 0 negative limit, bit 1 positive limit, bit 2 home switch
    uint16_t error_code = 0;  // 0x603F
};

struct Event {
    enum class Kind : uint8_t { Homing, Fault, Reset, Warning, Limit };
    double t_ms = 0;
    Kind kind = Kind::Homing;
    std::string text;
};

// CiA 402 state of a statusword: 0 not ready to switch on, 1 switch on disabled, 2 ready to switch on,
// 3 switched on, 4 operation enabled, 5 quick stop active, 6 fault reaction active, 7 fault; -1 none.
int cia402_state(uint16_t statusword);

// Changes between consecutive samples worth a mark on the plot.
std::vector<Event> find_events(const std::vector<Sample>& samples);

// CSV columns: t_ms, setpoint, position_demand, position_actual, velocity_actual_rpm, velocity_demand_rpm,
// current_ma, following_error, statusword, mode, digital_inputs, error_code, state.
// write_csv(path) leaves errno set when it fails.
bool write_csv(const std::string& path, const std::vector<Sample>& samples);
void write_csv(std::ostream& out, const std::vector<Sample>& samples);

// The gnuplot script that renders csv into png.
std::string gnuplot_script(const std::string& csv, const std::string& png, const std::string& title,
                           double end_ms, const std::vector<Event>& events);

}  // namespace drivesim
