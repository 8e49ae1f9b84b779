#include "drive/drive.hpp"

#include <cmath>
#include <cstring>
#include <stdexcept>

namespace drive {

bool Drive::locate(uint16_t index, uint8_t sub, std::size_t size, Link& link) {
    const od::Entry* e = dict_.find(index, sub);
    if (!e || e->byte_size() != size) {
        ++missing_;
        return false;
    }
    try {
        if (size == 1)
            link.r8 = dict_.ref<uint8_t>(index, sub);
        else if (size == 2)
            link.r16 = dict_.ref<uint16_t>(index, sub);
        else
            link.r32 = dict_.ref<uint32_t>(index, sub);
    } catch (const std::exception&) {
        ++missing_;
        return false;
    }
    link.size = static_cast<uint8_t>(size);
    ++bound_;
    return true;
}

void Drive::load(const Link& l) {
    if (l.size == 1) {
        const uint8_t v = l.r8.get();
        std::memcpy(l.field, &v, 1);
    } else if (l.size == 2) {
        const uint16_t v = l.r16.get();
        std::memcpy(l.field, &v, 2);
    } else {
        const uint32_t v = l.r32.get();
        std::memcpy(l.field, &v, 4);
    }
}

void Drive::store(Link l) {
    if (l.size == 1) {
        uint8_t v;
        std::memcpy(&v, l.field, 1);
        l.r8.set(v);
    } else if (l.size == 2) {
        uint16_t v;
        std::memcpy(&v, l.field, 2);
        l.r16.set(v);
    } else {
        uint32_t v;
        std::memcpy(&v, l.field, 4);
        l.r32.set(v);
    }
}

template <typename T>
void Drive::in(uint16_t index, uint8_t sub, T& field) {
    static_assert(sizeof(T) == 1 || sizeof(T) == 2 || sizeof(T) == 4);
    Link l{};
    l.field = reinterpret_cast<uint8_t*>(&field);
    if (locate(index, sub, sizeof(T), l)) inputs_.push_back(l);
}

template <typename T>
void Drive::out(uint16_t index, uint8_t sub, const T& field) {
    static_assert(sizeof(T) == 1 || sizeof(T) == 2 || sizeof(T) == 4);
    Link l{};
    l.field = reinterpret_cast<uint8_t*>(const_cast<T*>(&field));
    if (locate(index, sub, sizeof(T), l)) outputs_.push_back(l);
}

Drive::Drive(od::Dictionary& dictionary, EventSink* sink) : dict_(dictionary), axis_(sink) {
    Parameters& p = axis_.params;
    Command& c = axis_.command;
    // Configuration
    in(0x3001, 1, p.nominal_current);
    in(0x3001, 2, p.output_current_limit);
    in(0x3001, 3, p.pole_pairs);
    in(0x3001, 4, p.thermal_time_constant);
    in(0x3001, 5, p.torque_constant);
    in(0x6402, 0, p.motor_type);
    in(0x3010, 1, p.encoder_pulses);
    in(0x3010, 2, p.encoder_type);
    in(0x3000, 4, p.axis_misc);
    in(0x30A0, 1, p.current_p);
    in(0x30A0, 2, p.current_i);
    in(0x30A0, 3, p.current_ff);
    in(0x30A1, 1, p.bandwidth);
    in(0x30A1, 2, p.damping);
    in(0x30A1, 3, p.reset_time);
    in(0x30A1, 4, p.inertia);
    in(0x30A1, 5, p.friction);
    in(0x6007, 0, p.abort_connection);
    in(0x605A, 0, p.quick_stop);
    in(0x605B, 0, p.shutdown);
    in(0x605C, 0, p.disable_operation);
    in(0x605D, 0, p.halt);
    in(0x605E, 0, p.fault_reaction);
    in(0x6065, 0, p.following_error_window);
    in(0x6066, 0, p.following_error_timeout);
    in(0x607D, 1, p.sw_limit_min);
    in(0x607D, 2, p.sw_limit_max);
    in(0x607B, 1, p.range_min);
    in(0x607B, 2, p.range_max);
    in(0x607F, 0, p.max_profile_velocity);
    in(0x6080, 0, p.max_motor_speed);
    in(0x6081, 0, p.profile_velocity);
    in(0x6083, 0, p.profile_acceleration);
    in(0x6084, 0, p.profile_deceleration);
    in(0x6085, 0, p.quick_stop_deceleration);
    in(0x60C5, 0, p.max_acceleration);
    in(0x6098, 0, p.homing_method);
    in(0x6099, 1, p.homing_speed_switch);
    in(0x6099, 2, p.homing_speed_zero);
    in(0x609A, 0, p.homing_acceleration);
    in(0x30B0, 0, p.home_position);
    in(0x30B1, 0, p.home_offset_move);
    in(0x30B2, 0, p.homing_current_threshold);
    in(0x60C2, 1, p.interpolation_value);
    in(0x60C2, 2, p.interpolation_index);
    in(0x30E0, 1, p.standstill_window);
    in(0x30E0, 2, p.standstill_time);
    in(0x30E0, 3, p.standstill_timeout);
    in(0x3141, 2, p.input_polarity);
    for (uint8_t i = 0; i < 6; ++i)
        in(0x3142, static_cast<uint8_t>(i + 1), p.input_function[i]);
    in(0x60D0, 1, p.touch_probe_source);
    // Commands (RxPDO objects)
    in(0x6040, 0, c.controlword);
    in(0x6060, 0, c.mode);
    in(0x607A, 0, c.target_position);
    in(0x60FF, 0, c.target_velocity);
    in(0x6071, 0, c.target_torque);
    in(0x60B0, 0, c.position_offset);
    in(0x60B1, 0, c.velocity_offset);
    in(0x60B2, 0, c.torque_offset);
    in(0x60B8, 0, c.touch_probe_function);
    // Feedback (TxPDO objects and other computed values)
    Feedback& f = fb_copy_;
    out(0x6041, 0, f.statusword);
    out(0x6061, 0, f.mode_display);
    out(0x6062, 0, f.position_demand);
    out(0x6064, 0, f.position_actual);
    out(0x60E4, 1, f.position_actual);
    out(0x606B, 0, f.velocity_demand);
    out(0x606C, 0, f.velocity_actual);
    out(0x60E5, 1, f.velocity_actual);
    out(0x60E5, 9, f.velocity_averaged);
    out(0x30D5, 0, f.velocity_averaged);
    out(0x6077, 0, f.torque_actual);
    out(0x6078, 0, f.current_actual);
    out(0x30D0, 0, f.current_demand);
    out(0x30D1, 0, f.current_averaged);
    out(0x60F4, 0, f.following_error);
    out(0x6076, 0, f.motor_rated_torque);
    out(0x60FD, 0, f.digital_inputs);
    out(0x3141, 1, f.input_logic_state);
    out(0x3010, 4, f.index_position);
    out(0x60B9, 0, f.touch_probe_status);
    out(0x60BA, 0, f.touch_probe_pos);
    out(0x60BB, 0, f.touch_probe_neg);
    out(0x60D5, 0, f.touch_probe_pos_count);
    out(0x60D6, 0, f.touch_probe_neg_count);
    out(0x603F, 0, f.error_code);
    out(0x1001, 0, f.error_register);
    out(0x3000, 5, resolution_);

    const uint16_t power_disable_only[] = {0x3000, 0x3001, 0x3010, 0x3011, 0x3012, 0x3014,
                                           0x301A, 0x3020, 0x60A8, 0x60A9, 0x60AA, 0x6402};
    for (uint16_t index : power_disable_only) {
        if (!dict_.find(index)) continue;
        dict_.add_validator(index, [flag = powered_](const od::Entry& e, std::span<const uint8_t>) {
            if (e.index == 0x3001 && e.subindex != 3) return od::Status::Ok;  // only the pole pairs
            return flag->load(std::memory_order_relaxed) ? od::Status::WrongState : od::Status::Ok;
        });
    }
}

Drive::~Drive() {
    powered_->store(false);
}

od::Status commission(od::Dictionary& d, const MotorModel& m) {
    const double j = m.rotor_inertia + m.load_inertia;
    const struct {
        uint16_t index;
        uint8_t sub;
        uint32_t value;
    } rows[] = {
        {0x3001, 5, static_cast<uint32_t>(std::lround(m.torque_constant * 1e6))},  // uNm/A
        {0x30A1, 1, 20000},                                                        // 20 Hz
        {0x30A1, 2, 1000},                                                         // critical damping
        {0x30A1, 3, 50000},                                                        // 50 ms
        {0x30A1, 4, static_cast<uint32_t>(std::lround(j * 1e10))},                 // mg cm^2
        {0x30A1, 5, static_cast<uint32_t>(std::lround(m.viscous_friction * 1e9 * 6.283185307179586 / 60.0))},
    };
    for (const auto& r : rows) {
        const od::Status s = d.set<uint32_t>(r.index, r.sub, r.value);
        if (s != od::Status::Ok) return s;
    }
    return od::Status::Ok;
}

void Drive::cycle(int64_t now_ns, int64_t dt_ns) {
    for (const Link& l : inputs_)
        load(l);
    axis_.cycle(now_ns, dt_ns);
    fb_copy_ = axis_.feedback();
    resolution_ = axis_.increments_per_rev();
    for (const Link& l : outputs_)
        store(l);
    powered_->store(axis_.power_on(), std::memory_order_relaxed);
}

void Drive::connection_lost() {
    axis_.connection_lost();
    fb_copy_ = axis_.feedback();
    for (const Link& l : outputs_)
        store(l);
}

}  // namespace drive
