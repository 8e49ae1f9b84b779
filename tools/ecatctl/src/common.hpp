#pragma once
// Helpers the ecatctl commands share (main.cpp, cmd_firmware.cpp).
#include <string>

#include "master/coe.hpp"
#include "master/master.hpp"

namespace ecatctl {

// The exit code for a master error (the kExit* codes of format.hpp).
int exit_code(master::Error e);

// The end of a failed SDO transfer: an SDO abort (code and text) or a mailbox error of sdo is reported here
// (kExitProtocol); any other error goes to the caller's fail(e, what).
int report_sdo_failure(const master::SdoClient& sdo, master::Error e, const std::string& what,
                       int (*fail)(master::Error, const std::string&));

}  // namespace ecatctl
