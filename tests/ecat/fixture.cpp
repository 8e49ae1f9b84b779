#include "fixture.hpp"

#include <algorithm>

namespace ecat::test {

using od::access::RO;
using od::access::RW;
using od::access::RW_PreOp;

// ---- Master -----------------------------------------------------------------------------------------

uint16_t Master::exchange(esc::Command cmd, uint32_t address, std::span<uint8_t> data) {
    const std::size_t dlen = 10 + data.size() + 2;
    std::vector<uint8_t> f(std::max<std::size_t>(14 + 2 + dlen, 60), 0);
    std::fill(f.begin(), f.begin() + 6, uint8_t{0xFF});
    std::fill(f.begin() + 6, f.begin() + 12, uint8_t{0x01});
    f[12] = 0x88;
    f[13] = 0xA4;
    const uint16_t eh = static_cast<uint16_t>(dlen | (1u << 12));
    f[14] = static_cast<uint8_t>(eh);
    f[15] = static_cast<uint8_t>(eh >> 8);
    uint8_t* d = f.data() + 16;
    d[0] = static_cast<uint8_t>(cmd);
    d[1] = index_++;
    for (int i = 0; i < 4; ++i)
        d[2 + i] = static_cast<uint8_t>(address >> (8 * i));
    d[6] = static_cast<uint8_t>(data.size());
    d[7] = static_cast<uint8_t>((data.size() >> 8) & 0x07);
    std::copy(data.begin(), data.end(), d + 10);
    const bool back = esc_->process_frame(f);
    EXPECT_TRUE(back);
    std::copy(d + 10, d + 10 + data.size(), data.begin());
    return static_cast<uint16_t>(d[10 + data.size()] | (d[11 + data.size()] << 8));
}

uint16_t Master::write(uint16_t ado, std::span<const uint8_t> data) {
    std::vector<uint8_t> b(data.begin(), data.end());
    return exchange(esc::Command::APWR, static_cast<uint32_t>(ado) << 16, b);  // ADP 0: the first slave
}

uint16_t Master::read(uint16_t ado, std::span<uint8_t> data) {
    return exchange(esc::Command::APRD, static_cast<uint32_t>(ado) << 16, data);
}

// ---- Sample device ----------------------------------------------------------------------------------

namespace {

od::Entry entry(uint8_t sub, od::DataType type, uint16_t access, uint64_t def, std::string name = "") {
    od::Entry e;
    e.subindex = sub;
    e.type = type;
    e.access = access;
    e.default_value = def;
    e.name = name.empty() ? "Sub " + std::to_string(sub) : name;
    return e;
}

od::Object var(uint16_t index, od::DataType type, uint16_t access, uint64_t def = 0) {
    od::Object o;
    o.index = index;
    o.code = od::ObjectCode::Var;
    o.type = type;
    o.name = "Object";
    o.entries.push_back(entry(0, type, access, def));
    return o;
}

od::Object array(uint16_t index, od::DataType type, uint16_t access, std::vector<uint64_t> values,
                 uint8_t count, uint16_t count_access) {
    od::Object o;
    o.index = index;
    o.code = od::ObjectCode::Array;
    o.type = type;
    o.name = "Array";
    o.entries.push_back(entry(0, od::DataType::Unsigned8, count_access, count));
    for (std::size_t i = 0; i < values.size(); ++i)
        o.entries.push_back(entry(static_cast<uint8_t>(i + 1), type, access, values[i]));
    return o;
}

od::Object sync_params(uint16_t index) {
    od::Object o;
    o.index = index;
    o.code = od::ObjectCode::Record;
    o.type = od::DataType::SyncManagerParameter;
    o.name = "SM parameter";
    o.entries.push_back(entry(0, od::DataType::Unsigned8, RO, 0x20));
    o.entries.push_back(entry(1, od::DataType::Unsigned16, RW_PreOp, 1, "Sync mode"));
    o.entries.push_back(entry(2, od::DataType::Unsigned32, RW_PreOp, 1'000'000, "Cycle time"));
    o.entries.push_back(entry(3, od::DataType::Unsigned32, RO, 0, "Shift time"));
    o.entries.push_back(entry(4, od::DataType::Unsigned16, RO, 0x0006, "Sync modes supported"));
    o.entries.push_back(entry(5, od::DataType::Unsigned32, RO, 100'000, "Minimum cycle time"));
    o.entries.push_back(entry(0x0B, od::DataType::Unsigned16, RO, 0, "SM event missed counter"));
    o.entries.push_back(entry(0x0C, od::DataType::Unsigned16, RO, 0, "Cycle exceeded counter"));
    o.entries.push_back(entry(0x20, od::DataType::Boolean, RO, 0, "Sync error"));
    return o;
}

}  // namespace

od::Dictionary make_dictionary() {
    using od::DataType;
    od::Dictionary d;
    d.add(var(0x1000, DataType::Unsigned32, RO, 0x00020192));
    d.add(array(0x1600, DataType::Unsigned32, RW_PreOp, {0x60400010, 0x607A0020, 0, 0, 0, 0, 0, 0}, 2,
                RW_PreOp));
    d.add(array(0x1601, DataType::Unsigned32, RW_PreOp, {0, 0, 0, 0, 0, 0, 0, 0}, 0, RW_PreOp));
    d.add(array(0x1A00, DataType::Unsigned32, RW_PreOp, {0x60410010, 0x60640020, 0, 0, 0, 0, 0, 0}, 2,
                RW_PreOp));
    d.add(array(0x1A01, DataType::Unsigned32, RW_PreOp, {0, 0, 0, 0, 0, 0, 0, 0}, 0, RW_PreOp));
    d.add(array(0x1C00, DataType::Unsigned8, RO, {0, 0, 0, 0}, 4, RO));
    d.add(array(0x1C12, DataType::Unsigned16, RW_PreOp, {0x1600, 0x1601}, 1, RW_PreOp));
    d.add(array(0x1C13, DataType::Unsigned16, RW_PreOp, {0x1A00, 0x1A01}, 1, RW_PreOp));
    d.add(sync_params(0x1C32));
    d.add(sync_params(0x1C33));
    od::Object bits = array(0x2000, DataType::Boolean, RW | od::access::RxPdo | od::access::TxPdo,
                            {0, 0, 0, 0, 0, 0, 0, 0}, 8, RO);
    d.add(bits);
    d.add(var(0x6040, DataType::Unsigned16, RW | od::access::RxPdo));
    d.add(var(0x6041, DataType::Unsigned16, RO | od::access::TxPdo));
    d.add(var(0x6060, DataType::Integer8, RW | od::access::RxPdo));
    d.add(var(0x6064, DataType::Integer32, RO | od::access::TxPdo));
    d.add(var(0x607A, DataType::Integer32, RW | od::access::RxPdo));
    return d;
}

od::DeviceDescription make_description() {
    od::DeviceDescription d;
    d.identity.product_code = 0x30010000;
    d.standard_mailbox = {0x1000, 128, 0x1080, 128};
    d.bootstrap_mailbox = {0x1000, 256, 0x1100, 256};
    d.mailbox_protocols = od::mailbox_protocol::CoE | od::mailbox_protocol::FoE;
    d.sync_managers = {{od::SmKind::MBoxOut, 0x1000, 128, 0x26, true},
                       {od::SmKind::MBoxIn, 0x1080, 128, 0x22, true},
                       {od::SmKind::Outputs, kSm2Start, 6, 0x64, true},
                       {od::SmKind::Inputs, kSm3Start, 6, 0x20, true}};
    d.station_alias = 0x1234;
    return d;
}

// ---- Fixture ----------------------------------------------------------------------------------------

StackTest::StackTest() : dict(make_dictionary()), desc(make_description()) {
    clock.set(1'000'000'000);
}
StackTest::~StackTest() = default;

void StackTest::start() {
    stack.reset();
    esc = std::make_unique<esc::Esc>(esc::EscConfig{}, clock);
    master.attach(*esc);
    stack = std::make_unique<Stack>(*esc, dict, desc, app, [this] { return esc->irq(); });
    poll();
}

void StackTest::poll() {
    esc->tick();
    stack->poll(clock.now_ns());
}

void StackTest::advance(uint64_t ns) {
    clock.advance(ns);
    poll();
}

void StackTest::request(uint16_t control) {
    master.wr<uint16_t>(0x0120, control);
    poll();
}

void StackTest::configure_sm(unsigned n, uint16_t start_address, uint16_t length, uint8_t control,
                             bool enable) {
    uint8_t b[8] = {static_cast<uint8_t>(start_address),
                    static_cast<uint8_t>(start_address >> 8),
                    static_cast<uint8_t>(length),
                    static_cast<uint8_t>(length >> 8),
                    control,
                    0,
                    static_cast<uint8_t>(enable ? 1 : 0),
                    0};
    // Disable first (configuration is locked while enabled), then write all 8 bytes as masters do.
    master.wr<uint8_t>(static_cast<uint16_t>(0x0806 + 8 * n), 0);
    master.write(static_cast<uint16_t>(0x0800 + 8 * n), b);
}

void StackTest::configure_fmmu(unsigned n, uint32_t logical, uint16_t length, uint16_t physical,
                               uint8_t type) {
    uint8_t b[16] = {};
    for (int i = 0; i < 4; ++i)
        b[i] = static_cast<uint8_t>(logical >> (8 * i));
    b[4] = static_cast<uint8_t>(length);
    b[5] = static_cast<uint8_t>(length >> 8);
    b[6] = 0;
    b[7] = 7;
    b[8] = static_cast<uint8_t>(physical);
    b[9] = static_cast<uint8_t>(physical >> 8);
    b[10] = 0;
    b[11] = type;
    b[12] = 1;
    master.write(static_cast<uint16_t>(0x0600 + 16 * n), b);
}

void StackTest::configure_mailbox() {
    configure_sm(0, 0x1000, 128, 0x26, true);
    configure_sm(1, 0x1080, 128, 0x22, true);
}

void StackTest::configure_bootstrap_mailbox() {
    configure_sm(0, 0x1000, 256, 0x26, true);
    configure_sm(1, 0x1100, 256, 0x22, true);
}

void StackTest::configure_process_data(uint16_t rx, uint16_t tx, uint8_t sm2_control) {
    rx_bytes = rx;
    tx_bytes = tx;
    const uint16_t sm2 = desc.sync_managers.size() > 2 && desc.sync_managers[2].start
                             ? desc.sync_managers[2].start
                             : kSm2Start;
    const uint16_t sm3 = desc.sync_managers.size() > 3 && desc.sync_managers[3].start
                             ? desc.sync_managers[3].start
                             : kSm3Start;
    configure_sm(2, sm2, rx, sm2_control, rx > 0);
    configure_sm(3, sm3, tx, 0x20, tx > 0);
    if (rx > 0) configure_fmmu(0, kLogical, rx, sm2, 2);
    if (tx > 0) configure_fmmu(1, kLogical + rx, tx, sm3, 1);
}

void StackTest::go_preop() {
    configure_mailbox();
    request(0x02);
    ASSERT_EQ(al_status(), 0x02) << "code " << std::hex << al_code();
}

void StackTest::go_safeop() {
    go_preop();
    configure_process_data(6, 6);
    request(0x04);
    ASSERT_EQ(al_status(), 0x04) << "code " << std::hex << al_code();
}

void StackTest::go_op() {
    go_safeop();
    std::vector<uint8_t> out(rx_bytes, 0), in(tx_bytes, 0);
    exchange_pd(out, in);
    poll();
    request(0x08);
    ASSERT_EQ(al_status(), 0x08) << "code " << std::hex << al_code();
}

uint16_t StackTest::exchange_pd(std::span<const uint8_t> out, std::span<uint8_t> in) {
    std::vector<uint8_t> image(rx_bytes + tx_bytes, 0);
    std::copy(out.begin(), out.end(), image.begin());
    const uint16_t wkc = master.lrw(kLogical, image);
    std::copy(image.begin() + rx_bytes, image.end(), in.begin());
    return wkc;
}

void StackTest::mbx_write(std::span<const uint8_t> message) {
    const uint16_t size = master.rd<uint16_t>(0x0802);
    std::vector<uint8_t> b(size, 0);
    std::copy(message.begin(), message.begin() + std::min<std::size_t>(message.size(), size), b.begin());
    const uint16_t start_address = master.rd<uint16_t>(0x0800);
    EXPECT_EQ(master.write(start_address, b), 1) << "SM0 write refused";
}

std::vector<uint8_t> StackTest::mbx_read() {
    const uint16_t size = master.rd<uint16_t>(0x080A);
    const uint16_t start_address = master.rd<uint16_t>(0x0808);
    std::vector<uint8_t> b(size, 0);
    if (master.read(start_address, b) != 1) return {};
    return b;
}

std::vector<uint8_t> StackTest::mbx_message(uint8_t type, uint8_t counter, std::span<const uint8_t> payload,
                                            uint16_t address, uint8_t channel) {
    std::vector<uint8_t> m(6 + payload.size());
    m[0] = static_cast<uint8_t>(payload.size());
    m[1] = static_cast<uint8_t>(payload.size() >> 8);
    m[2] = static_cast<uint8_t>(address);
    m[3] = static_cast<uint8_t>(address >> 8);
    m[4] = channel;
    m[5] = static_cast<uint8_t>((type & 0x0F) | ((counter & 7) << 4));
    std::copy(payload.begin(), payload.end(), m.begin() + 6);
    return m;
}

}  // namespace ecat::test
