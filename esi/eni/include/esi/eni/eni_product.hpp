#pragma once
// An ENI slave as a product (od::Product): for a slave of a line whose vendor ESI is not at hand, what the
// master was configured with is enough for a process-data slave (issue 21, part 4):
//
//   identity     Info VendorId/ProductCode/RevisionNo/SerialNo; the name is Info/Name, the order code the
//                text in its last parentheses ("Term 2 (EL1008)" -> EL1008);
//   SyncManagers ProcessData/Sm0..Sm7 (start, control byte, enable), else the Mailbox areas for SM0/SM1;
//                a process-data SM's default size is the bits of the PDOs assigned to it;
//   PDOs         every RxPdo/TxPdo as a mapping object (0x16xx/0x1Axx; read-only when Fixed), the SM
//                assignment (0x1C10+n for SM n: 0x1C12/0x1C13 on a slave with a mailbox) as the ENI assigns;
//                every mapped entry gets its object and storage (outputs rw and RxPDO-mappable, inputs ro and
//                TxPDO-mappable);
//   mailbox      the areas and protocols declared; CoE and FoE are served, the others answered with the
//                mailbox error for an unsupported protocol and named in a warning;
//   CoE          the objects the master reads or writes in its CoE InitCmds exist, writable in Pre-Op and
//                Safe-Op and holding what the master writes: an ENI does not carry the slave's dictionary,
//                and a master that gets an abort for an init command stops before Op (docs/eni.md);
//   DC           the AssignActivate the master writes to 0x0980 (or DC/AssignActivate) as the DC op mode.
//
// Whatever the ENI declares that is not emulated is one line of Product::warnings.
#include <cstddef>

#include "esi/eni/eni_reader.hpp"
#include "od/product.hpp"

namespace esi::eni {

// The product of config.slaves[slave]. Throws EniError "FILE:LINE: message" for a slave that cannot be built
// (an entry declared with two sizes, a PDO beyond its SyncManager).
od::Product product_from_eni(const Config& config, std::size_t slave);

}  // namespace esi::eni
