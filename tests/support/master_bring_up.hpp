#pragma once
// Bringing up a bus of one in-process slave with the master library, as the tests of master, device and foe
// all start: count it, give it its station address, then (for most) its standard mailbox and PRE-OP.
// Call through ASSERT_NO_FATAL_FAILURE(...) so a failed step stops the test.
#include <gtest/gtest.h>

#include <chrono>
#include <ios>

#include "master/mailbox.hpp"
#include "master/master.hpp"

namespace test_support {

// Master options for an in-process slave: it answers at once, so short frame timeouts; AL state changes
// still get half a second.
inline master::MasterOptions in_process_master_options() {
    master::MasterOptions o;
    o.timeout = std::chrono::milliseconds(5);
    o.al_timeout = std::chrono::milliseconds(500);
    return o;
}

// The one slave on the bus counted and given its station address.
inline void one_slave_addressed(master::Master& m) {
    ASSERT_EQ(m.count_slaves().value(), 1);
    ASSERT_EQ(m.assign_station_addresses(1), master::Error::Ok);
}

// ... and its standard mailbox configured from the SII, then the slave in PRE-OP.
inline void one_slave_in_preop(master::Master& m, master::Mailbox& mbx, master::Address a) {
    ASSERT_NO_FATAL_FAILURE(one_slave_addressed(m));
    ASSERT_EQ(mbx.configure_from_sii(), master::Error::Ok);
    master::AlStatus st;
    ASSERT_EQ(m.request_state(a, master::AlState::PreOp, &st), master::Error::Ok)
        << "AL code 0x" << std::hex << st.code;
}

}  // namespace test_support
