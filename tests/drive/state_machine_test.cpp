// CiA 402 controlword decoding and the transition table (IEC 61800-7-201 §6.2.2; MAXPOS firmware
// specification Tables 3-5..3-7).
#include <gtest/gtest.h>

#include "drive/state_machine.hpp"

using namespace drive;

TEST(Controlword, DecodesTable3_7Patterns) {
    EXPECT_EQ(decode(0x0006, 0), DeviceCommand::Shutdown);
    EXPECT_EQ(decode(0x000E, 0), DeviceCommand::Shutdown);  // 0xxx x110: bit 3 don't care
    EXPECT_EQ(decode(0x0007, 0), DeviceCommand::SwitchOn);
    EXPECT_EQ(decode(0x000F, 0), DeviceCommand::EnableOperation);
    EXPECT_EQ(decode(0x0000, 0), DeviceCommand::DisableVoltage);
    EXPECT_EQ(decode(0x000D, 0), DeviceCommand::DisableVoltage);  // 0xxx xx0x
    EXPECT_EQ(decode(0x0002, 0), DeviceCommand::QuickStop);
    EXPECT_EQ(decode(0x000B, 0), DeviceCommand::QuickStop);        // the EPOS4 Application Notes use 0x000B
    EXPECT_EQ(decode(0x001F, 0), DeviceCommand::EnableOperation);  // mode bits do not matter
}

TEST(Controlword, FaultResetIsTheRisingEdgeOfBit7) {
    EXPECT_EQ(decode(0x0080, 0x0000), DeviceCommand::FaultReset);
    EXPECT_EQ(decode(0x0080, 0x0080), DeviceCommand::None);  // held high: nothing
    EXPECT_EQ(decode(0x008F, 0x0080), DeviceCommand::None);  // bit 7 set: no other command either
}

TEST(Transitions, EveryNumberedTransition) {
    using S = State;
    using C = DeviceCommand;
    struct Row {
        S from;
        C cmd;
        S to;
        int n;
    };
    const Row rows[] = {
        {S::SwitchOnDisabled, C::Shutdown, S::ReadyToSwitchOn, 2},
        {S::ReadyToSwitchOn, C::SwitchOn, S::SwitchedOn, 3},
        {S::SwitchedOn, C::EnableOperation, S::OperationEnabled, 4},
        {S::OperationEnabled, C::SwitchOn, S::SwitchedOn, 5},
        {S::SwitchedOn, C::Shutdown, S::ReadyToSwitchOn, 6},
        {S::ReadyToSwitchOn, C::DisableVoltage, S::SwitchOnDisabled, 7},
        {S::ReadyToSwitchOn, C::QuickStop, S::SwitchOnDisabled, 7},
        {S::OperationEnabled, C::Shutdown, S::ReadyToSwitchOn, 8},
        {S::OperationEnabled, C::DisableVoltage, S::SwitchOnDisabled, 9},
        {S::SwitchedOn, C::DisableVoltage, S::SwitchOnDisabled, 10},
        {S::SwitchedOn, C::QuickStop, S::SwitchOnDisabled, 10},
        {S::OperationEnabled, C::QuickStop, S::QuickStopActive, 11},
        {S::QuickStopActive, C::DisableVoltage, S::SwitchOnDisabled, 12},
        {S::Fault, C::FaultReset, S::SwitchOnDisabled, 15},
        {S::QuickStopActive, C::EnableOperation, S::OperationEnabled, 16},
        {S::ReadyToSwitchOn, C::EnableOperation, S::SwitchedOn, 3},  // then 4 automatically
    };
    for (const Row& r : rows) {
        const Transition t = next(r.from, r.cmd);
        EXPECT_EQ(t.to, r.to) << to_string(r.from);
        EXPECT_EQ(t.number, r.n) << to_string(r.from);
    }
}

TEST(Transitions, CommandsWithoutTransitionChangeNothing) {
    EXPECT_EQ(next(State::SwitchOnDisabled, DeviceCommand::EnableOperation).number, -1);
    EXPECT_EQ(next(State::Fault, DeviceCommand::Shutdown).number, -1);
    EXPECT_EQ(next(State::QuickStopActive, DeviceCommand::Shutdown).number, -1);
    EXPECT_EQ(next(State::FaultReactionActive, DeviceCommand::FaultReset).number, -1);
    EXPECT_EQ(next(State::OperationEnabled, DeviceCommand::EnableOperation).number, -1);
}

TEST(Statusword, StatePatternsIncludingBits4And5) {
    EXPECT_EQ(state_bits(State::NotReadyToSwitchOn), 0x00);
    EXPECT_EQ(state_bits(State::SwitchOnDisabled), 0x40);
    EXPECT_EQ(state_bits(State::ReadyToSwitchOn), 0x21);
    EXPECT_EQ(state_bits(State::SwitchedOn), 0x23);
    EXPECT_EQ(state_bits(State::OperationEnabled), 0x37);
    EXPECT_EQ(state_bits(State::QuickStopActive), 0x17);
    EXPECT_EQ(state_bits(State::FaultReactionActive, true), 0x1F);
    EXPECT_EQ(state_bits(State::FaultReactionActive, false), 0x0F);
    EXPECT_EQ(state_bits(State::Fault), 0x08);
}
