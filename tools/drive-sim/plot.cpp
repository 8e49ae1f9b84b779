// drive-sim's events and plot (see plot.hpp).
#include "plot.hpp"

#include <cerrno>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "drive/errors.hpp"

namespace drivesim {

int cia402_state(uint16_t sw) {
    if ((sw & 0x4F) == 0x00) return 0;
    if ((sw & 0x4F) == 0x40) return 1;
    if ((sw & 0x6F) == 0x21) return 2;
    if ((sw & 0x6F) == 0x23) return 3;
    if ((sw & 0x6F) == 0x27) return 4;
    if ((sw & 0x6F) == 0x07) return 5;
    if ((sw & 0x4F) == 0x0F) return 6;
    if ((sw & 0x4F) == 0x08) return 7;
    return -1;
}

namespace {

std::string hex4(uint16_t v) {
    char b[8];
    std::snprintf(b, sizeof b, "0x%04X", static_cast<unsigned>(v));
    return b;
}

bool rose(uint32_t before, uint32_t now, uint32_t bit) {
    return (now & bit) != 0 && (before & bit) == 0;
}
bool fell(uint32_t before, uint32_t now, uint32_t bit) {
    return (now & bit) == 0 && (before & bit) != 0;
}

// gnuplot single-quoted string: a quote is doubled.
std::string quoted(const std::string& s) {
    std::string out = "'";
    for (char c : s) {
        if (c == '\'') out += '\'';
        out += c;
    }
    return out + "'";
}

const char* colour(Event::Kind k) {
    switch (k) {
        case Event::Kind::Homing:
            return "#1a9850";
        case Event::Kind::Fault:
            return "#d73027";
        case Event::Kind::Reset:
            return "#4575b4";
        case Event::Kind::Warning:
            return "#fc8d59";
        case Event::Kind::Limit:
            return "#762a83";
    }
    return "#000000";
}

}  // namespace

std::vector<Event> find_events(const std::vector<Sample>& s) {
    std::vector<Event> ev;
    for (std::size_t i = 1; i < s.size(); ++i) {
        const Sample& a = s[i - 1];
        const Sample& b = s[i];
        const double t = b.t_ms;
        // Homing (0x6061 = 6): statusword bit 12 homing attained, bit 13 homing error.
        if (b.mode == 6 && rose(a.statusword, b.statusword, 0x1000))
            ev.push_back({t, Event::Kind::Homing, "homing done"});
        if (b.mode == 6 && rose(a.statusword, b.statusword, 0x2000))
            ev.push_back({t, Event::Kind::Fault, "homing error"});
        if (rose(a.statusword, b.statusword, 0x0008)) {
            const drive::ErrorInfo* info = drive::find_error(b.error_code);
            std::string text = "fault ";
            text.append(hex4(b.error_code));
            if (info != nullptr) text.append(" ").append(info->name);
            ev.push_back({t, Event::Kind::Fault, text});
        }
        if (fell(a.statusword, b.statusword, 0x0008)) ev.push_back({t, Event::Kind::Reset, "fault reset"});
        if (rose(a.statusword, b.statusword, 0x0080)) ev.push_back({t, Event::Kind::Warning, "warning"});
        if (rose(a.inputs, b.inputs, 0x1)) ev.push_back({t, Event::Kind::Limit, "negative limit switch on"});
        if (fell(a.inputs, b.inputs, 0x1)) ev.push_back({t, Event::Kind::Limit, "negative limit switch off"});
        if (rose(a.inputs, b.inputs, 0x2)) ev.push_back({t, Event::Kind::Limit, "positive limit switch on"});
        if (fell(a.inputs, b.inputs, 0x2)) ev.push_back({t, Event::Kind::Limit, "positive limit switch off"});
        if (rose(a.inputs, b.inputs, 0x4)) ev.push_back({t, Event::Kind::Limit, "home switch on"});
        if (fell(a.inputs, b.inputs, 0x4)) ev.push_back({t, Event::Kind::Limit, "home switch off"});
    }
    return ev;
}

void write_csv(std::ostream& f, const std::vector<Sample>& s) {
    f << "t_ms,setpoint,position_demand,position_actual,velocity_actual_rpm,velocity_demand_rpm,current_ma,"
         "following_error,statusword,mode,digital_inputs,error_code,state\n";
    for (const Sample& x : s)
        f << x.t_ms << ',' << x.setpoint << ',' << x.demand << ',' << x.actual << ',' << x.velocity << ','
          << x.velocity_demand << ',' << x.current << ',' << x.following_error << ",0x" << std::hex
          << x.statusword << std::dec << ',' << static_cast<int>(x.mode) << ",0x" << std::hex << x.inputs
          << ",0x" << x.error_code << std::dec << ',' << cia402_state(x.statusword) << '\n';
}

bool write_csv(const std::string& path, const std::vector<Sample>& s) {
    errno = 0;
    std::ofstream f(path);
    if (!f) return false;
    write_csv(f, s);
    return static_cast<bool>(f.flush());
}

std::string gnuplot_script(const std::string& csv, const std::string& png, const std::string& title,
                           double end_ms, const std::vector<Event>& events) {
    // Panels top to bottom with their share of the height; all share the left and right edges (so the
    // time axes line up) and the x range.
    struct Panel {
        double weight;
        const char* ylabel;
    };
    const Panel panels[] = {{3.0, "position [inc]"},        {2.2, "velocity [rpm]"}, {1.8, "current [mA]"},
                            {1.8, "following error [inc]"}, {0.9, "mode 0x6061"},    {1.3, "state 0x6041"}};
    constexpr double kTop = 0.93, kBottom = 0.05, kGap = 0.012;
    double total = 0;
    for (const Panel& p : panels)
        total += p.weight;
    const std::size_t n = std::size(panels);
    const double room = kTop - kBottom - kGap * static_cast<double>(n - 1);

    std::ostringstream g;
    g << "set datafile separator ','\n"
         "set terminal pngcairo size 1400,1300 noenhanced font ',10'\n"
         "set output "
      << quoted(png)
      << "\n"
         "set multiplot title "
      << quoted(title)
      << " font ',14'\n"
         "set lmargin at screen 0.08\nset rmargin at screen 0.86\n"
         "set grid\nset key outside right top Left reverse samplen 3 width 2\n"
         "set xrange [0:"
      << end_ms << "]\nset format x ''\nunset xlabel\nset ytics nomirror\n";
    // Events: a dashed line in every panel; the names on top of the first one, events closer than about a
    // character's width in one label (a fault and the switch that caused it), on a white box over the curves.
    g << "set style textbox opaque noborder\n";
    for (const Event& e : events)
        g << "set arrow from " << e.t_ms << ", graph 0 to " << e.t_ms
          << ", graph 1 nohead dt 2 lw 1.2 lc rgb '" << colour(e.kind) << "' back\n";
    int label = 1;
    const double close = end_ms * 0.012;
    for (std::size_t i = 0; i < events.size();) {
        std::size_t j = i + 1;
        std::string text = events[i].text;
        Event::Kind kind = events[i].kind;
        for (; j < events.size() && events[j].t_ms - events[i].t_ms <= close; ++j) {
            text += " / " + events[j].text;
            if (events[j].kind == Event::Kind::Fault) kind = Event::Kind::Fault;  // the fault's colour wins
        }
        g << "set label " << label++ << ' ' << quoted(text) << " at " << events[i].t_ms
          << ", graph 1 rotate by 90 right offset 1.1,-0.3 font ',8' tc rgb '" << colour(kind)
          << "' boxed front\n";
        i = j;
    }
    double top = kTop;
    for (std::size_t i = 0; i < n; ++i) {
        const double h = room * panels[i].weight / total;
        g << "set tmargin at screen " << top << "\nset bmargin at screen " << (top - h) << "\n";
        g << "set ylabel " << quoted(panels[i].ylabel) << "\n";
        top -= h + kGap;
        const std::string src = i == 0 ? quoted(csv) : std::string("''");
        switch (i) {
            case 0:
                g << "plot " << src
                  << " using 1:3 with lines lw 7 lc rgb '#9ecae1' title 'demand 0x6062', "
                     "'' using 1:4 with lines lw 1.6 lc rgb '#08306b' title 'actual 0x6064'\n"
                     "unset label\n";
                break;
            case 1:
                g << "plot " << src
                  << " using 1:6 with lines lw 7 lc rgb '#fdd0a2' title 'demand 0x606B', "
                     "'' using 1:5 with lines lw 1.6 lc rgb '#a63603' title 'actual 0x606C'\n";
                break;
            case 2:
                g << "plot " << src
                  << " using 1:7 with lines lw 1.4 lc rgb '#54278f' title 'actual 0x6078'\n";
                break;
            case 3:
                g << "plot " << src << " using 1:8 with lines lw 1.4 lc rgb '#b2182b' title '0x60F4'\n";
                break;
            case 4:
                // Modes on evenly spaced rows (their numbers 1, 3, 6, 8, 9, 10 would crowd the top).
                g << "mrow(m) = m == 1 ? 1 : m == 3 ? 2 : m == 6 ? 3 : m == 8 ? 4 : m == 9 ? 5 : m == 10 ? 6 "
                     ": 0\n"
                     "set yrange [-0.5:6.5]\nset ytics ('none' 0, 'PP' 1, 'PV' 2, 'HM' 3, 'CSP' 4, 'CSV' 5, "
                     "'CST' 6) font ',8'\nunset grid\nset grid xtics\n"
                     "plot "
                  << src << " using 1:(mrow($10)) with steps lw 2.5 lc rgb '#006d2c' title 'mode display'\n";
                break;
            default:
                g << "set yrange [-0.5:7.5]\nset ytics ('not ready' 0, 'sw-on disabled' 1, 'ready' 2, "
                     "'switched on' 3, 'op enabled' 4, 'quick stop' 5, 'fault reaction' 6, 'fault' 7) font "
                     "',8'\n"
                     "set format x '%g'\nset xlabel 't [ms]'\n"
                     "plot "
                  << src << " using 1:13 with steps lw 2.5 lc rgb '#252525' title 'CiA 402 state'\n";
                break;
        }
    }
    g << "unset multiplot\n";
    return g.str();
}

}  // namespace drivesim
