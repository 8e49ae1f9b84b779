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
    link.index = index;
    link.sub = sub;
    ++bound_;
    return true;
}

template <typename T>
void Drive::load(const std::vector<Link>& links) {
    for (const Link& l : links) {
        T v;
        if constexpr (sizeof(T) == 1)
            v = l.r8.get();
        else if constexpr (sizeof(T) == 2)
            v = l.r16.get();
        else
            v = l.r32.get();
        std::memcpy(l.field, &v, sizeof(T));
    }
}

template <typename T>
void Drive::store(const std::vector<Link>& links) {
    for (Link l : links) {
        T v;
        std::memcpy(&v, l.field, sizeof(T));
        if constexpr (sizeof(T) == 1)
            l.r8.set(v);
        else if constexpr (sizeof(T) == 2)
            l.r16.set(v);
        else
            l.r32.set(v);
    }
}

void Drive::load_inputs() {
    load<uint8_t>(inputs_[0]);
    load<uint16_t>(inputs_[1]);
    load<uint32_t>(inputs_[2]);
}

void Drive::store_outputs() {
    store<uint8_t>(outputs_[0]);
    store<uint16_t>(outputs_[1]);
    store<uint32_t>(outputs_[2]);
}

template <typename T>
void Drive::in(const od::Obj<T>& h, T& field) {
    static_assert(sizeof(T) == 1 || sizeof(T) == 2 || sizeof(T) == 4);
    Link l{};
    l.field = reinterpret_cast<uint8_t*>(&field);
    if (locate(h.index, h.sub, sizeof(T), l)) inputs_[group(sizeof(T))].push_back(l);
}

template <typename T>
void Drive::out(const od::Obj<T>& h, const T& field) {
    static_assert(sizeof(T) == 1 || sizeof(T) == 2 || sizeof(T) == 4);
    Link l{};
    l.field = reinterpret_cast<uint8_t*>(const_cast<T*>(&field));
    if (locate(h.index, h.sub, sizeof(T), l)) outputs_[group(sizeof(T))].push_back(l);
}

bool Drive::binds(uint16_t index, uint8_t sub) const {
    for (const auto* groups : {&inputs_, &outputs_})
        for (const auto& links : *groups)
            for (const Link& l : links)
                if (l.index == index && l.sub == sub) return true;
    return false;
}

Drive::Drive(od::Dictionary& dictionary, EventSink* sink) : dict_(dictionary), axis_(sink) {
    namespace obj = od::obj;
    Parameters& p = axis_.params;
    Command& c = axis_.command;
    // Configuration
    in(obj::MotorNominalCurrent, p.nominal_current);
    in(obj::MotorOutputCurrentLimit, p.output_current_limit);
    in(obj::MotorPolePairs, p.pole_pairs);
    in(obj::MotorThermalTimeConstant, p.thermal_time_constant);
    in(obj::MotorTorqueConstant, p.torque_constant);
    in(obj::MotorType, p.motor_type);
    in(obj::EncoderPulses, p.encoder_pulses);
    in(obj::EncoderType, p.encoder_type);
    in(obj::AxisConfigurationMisc, p.axis_misc);
    in(obj::CurrentPGain, p.current_p);
    in(obj::CurrentIGain, p.current_i);
    in(obj::CurrentFfGain, p.current_ff);
    in(obj::PositionBandwidth, p.bandwidth);
    in(obj::PositionDamping, p.damping);
    in(obj::PositionResetTime, p.reset_time);
    in(obj::Inertia, p.inertia);
    in(obj::Friction, p.friction);
    in(obj::AbortConnectionOptionCode, p.abort_connection);
    in(obj::QuickStopOptionCode, p.quick_stop);
    in(obj::ShutdownOptionCode, p.shutdown);
    in(obj::DisableOperationOptionCode, p.disable_operation);
    in(obj::HaltOptionCode, p.halt);
    in(obj::FaultReactionOptionCode, p.fault_reaction);
    in(obj::FollowingErrorWindow, p.following_error_window);
    in(obj::FollowingErrorTimeout, p.following_error_timeout);
    in(obj::SoftwarePositionLimitMin, p.sw_limit_min);
    in(obj::SoftwarePositionLimitMax, p.sw_limit_max);
    in(obj::PositionRangeLimitMin, p.range_min);
    in(obj::PositionRangeLimitMax, p.range_max);
    in(obj::MaxProfileVelocity, p.max_profile_velocity);
    in(obj::MaxMotorSpeed, p.max_motor_speed);
    in(obj::ProfileVelocity, p.profile_velocity);
    in(obj::ProfileAcceleration, p.profile_acceleration);
    in(obj::ProfileDeceleration, p.profile_deceleration);
    in(obj::QuickStopDeceleration, p.quick_stop_deceleration);
    in(obj::MaxAcceleration, p.max_acceleration);
    in(obj::HomingMethod, p.homing_method);
    in(obj::HomingSpeedSwitchSearch, p.homing_speed_switch);
    in(obj::HomingSpeedZeroSearch, p.homing_speed_zero);
    in(obj::HomingAcceleration, p.homing_acceleration);
    in(obj::HomePosition, p.home_position);
    in(obj::HomeOffsetMoveDistance, p.home_offset_move);
    in(obj::HomingCurrentThreshold, p.homing_current_threshold);
    in(obj::InterpolationTimePeriodValue, p.interpolation_value);
    in(obj::InterpolationTimeIndex, p.interpolation_index);
    in(obj::StandstillWindow, p.standstill_window);
    in(obj::StandstillWindowTime, p.standstill_time);
    in(obj::StandstillWindowTimeout, p.standstill_timeout);
    in(obj::DigitalInputPolarity, p.input_polarity);
    in(obj::DigitalInput1Configuration, p.input_function[0]);
    in(obj::DigitalInput2Configuration, p.input_function[1]);
    in(obj::DigitalInput3Configuration, p.input_function[2]);
    in(obj::DigitalInput4Configuration, p.input_function[3]);
    in(obj::DigitalInput5Configuration, p.input_function[4]);
    in(obj::DigitalInput6Configuration, p.input_function[5]);
    in(obj::TouchProbe1Source, p.touch_probe_source);
    // Commands (RxPDO objects)
    in(obj::Controlword, c.controlword);
    in(obj::ModesOfOperation, c.mode);
    in(obj::TargetPosition, c.target_position);
    in(obj::TargetVelocity, c.target_velocity);
    in(obj::TargetTorque, c.target_torque);
    in(obj::PositionOffset, c.position_offset);
    in(obj::VelocityOffset, c.velocity_offset);
    in(obj::TorqueOffset, c.torque_offset);
    in(obj::TouchProbeFunction, c.touch_probe_function);
    // Feedback (TxPDO objects and other computed values)
    Feedback& f = fb_copy_;
    out(obj::Statusword, f.statusword);
    out(obj::ModesOfOperationDisplay, f.mode_display);
    out(obj::PositionDemandValue, f.position_demand);
    out(obj::PositionActualValue, f.position_actual);
    out(obj::PositionActualValueSensor1, f.position_actual);
    out(obj::VelocityDemandValue, f.velocity_demand);
    out(obj::VelocityActualValue, f.velocity_actual);
    out(obj::VelocityActualValueSensor1, f.velocity_actual);
    out(obj::VelocityActualAveragedSensor1, f.velocity_averaged);
    out(obj::VelocityActualValueAveraged, f.velocity_averaged);
    out(obj::TorqueActualValue, f.torque_actual);
    out(obj::CurrentActualValue, f.current_actual);
    out(obj::CurrentDemandValue, f.current_demand);
    out(obj::CurrentActualValueAveraged, f.current_averaged);
    out(obj::FollowingErrorActualValue, f.following_error);
    out(obj::MotorRatedTorque, f.motor_rated_torque);
    out(obj::DigitalInputs, f.digital_inputs);
    out(obj::DigitalInputLogicState, f.input_logic_state);
    out(obj::EncoderIndexPosition, f.index_position);
    out(obj::TouchProbeStatus, f.touch_probe_status);
    out(obj::TouchProbePosition1Positive, f.touch_probe_pos);
    out(obj::TouchProbePosition1Negative, f.touch_probe_neg);
    out(obj::TouchProbe1PositiveEdgeCounter, f.touch_probe_pos_count);
    out(obj::TouchProbe1NegativeEdgeCounter, f.touch_probe_neg_count);
    out(obj::ErrorCode, f.error_code);
    out(obj::ErrorRegister, f.error_register);
    out(obj::MainSensorResolution, resolution_);

    const uint16_t power_disable_only[] = {obj::AxisConfiguration,
                                           obj::MotorData,
                                           obj::DigitalIncrementalEncoder1,
                                           obj::AnalogIncrementalEncoder,
                                           obj::SsiAbsoluteEncoder,
                                           obj::BissAbsoluteEncoder,
                                           obj::DigitalHallSensor,
                                           obj::DigitalIncrementalEncoder2,
                                           obj::SiUnitPosition,
                                           obj::SiUnitVelocity,
                                           obj::SiUnitAcceleration,
                                           obj::MotorType.index};
    for (uint16_t index : power_disable_only) {
        if (!dict_.find(index)) continue;
        // Owned by this drive (removed by its destructor): a dictionary that outlives its drive, or serves
        // one drive after another, keeps no validator of a drive that is gone.
        dict_.add_validator(
            index,
            [flag = powered_](const od::Entry& e, std::span<const uint8_t>) {
                if (e.index == obj::MotorData && e.subindex != obj::MotorPolePairs.sub)
                    return od::Status::Ok;  // only the pole pairs
                return flag->load(std::memory_order_relaxed) ? od::Status::WrongState : od::Status::Ok;
            },
            this);
    }
}

Drive::~Drive() {
    powered_->store(false);
    dict_.remove_hooks(this);
}

od::Status commission(od::Dictionary& d, const MotorModel& m) {
    const double j = m.rotor_inertia + m.load_inertia;
    const struct {
        od::Obj<uint32_t> obj;
        uint32_t value;
    } rows[] = {
        {od::obj::MotorTorqueConstant, static_cast<uint32_t>(std::lround(m.torque_constant * 1e6))},  // uNm/A
        {od::obj::PositionBandwidth, 20000},                                                          // 20 Hz
        {od::obj::PositionDamping, 1000},                                  // critical damping
        {od::obj::PositionResetTime, 50000},                               // 50 ms
        {od::obj::Inertia, static_cast<uint32_t>(std::lround(j * 1e10))},  // mg cm^2
        {od::obj::Friction,
         static_cast<uint32_t>(std::lround(m.viscous_friction * 1e9 * 6.283185307179586 / 60.0))},
    };
    for (const auto& r : rows) {
        const od::Status s = d.set<uint32_t>(r.obj.index, r.obj.sub, r.value);
        if (s != od::Status::Ok) return s;
    }
    return od::Status::Ok;
}

void Drive::cycle(int64_t now_ns, int64_t dt_ns) {
    load_inputs();
    axis_.cycle(now_ns, dt_ns);
    fb_copy_ = axis_.feedback();
    resolution_ = static_cast<uint32_t>(axis_.increments_per_rev());
    store_outputs();
    powered_->store(axis_.power_on(), std::memory_order_relaxed);
}

void Drive::connection_lost() {
    axis_.connection_lost();
    fb_copy_ = axis_.feedback();
    store_outputs();
}

}  // namespace drive
