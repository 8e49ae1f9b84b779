#!/usr/bin/env python3
"""A test master that sends what the IgH EtherCAT master sends, for the replay corpus (igh-*.pcap.gz).

IgH's master runs as a kernel module and cannot run here. This program sends the datagram sequence of its state
machines as its source code has them (https://github.com/ribalda/ethercat, the IgH master's git mirror, commit
97e7ee64a6b4a2e3847270797cae681b8484a7d0; file and function named at each step). It is written from reading that
code; none of it is copied. One FSM datagram per frame, as IgH's master FSM keeps one datagram in flight; once the
application is active (ecrt_master_activate), every frame also carries the application's cyclic datagrams, and
frames go out every millisecond, as ecrt_master_send() in a 1 ms task does.

    igh_master.py IFACE [--seconds S]

The application it plays is a CiA 402 drive configured as IgH's examples configure one: operation mode 8 (CSP)
by an SDO at start-up (ecrt_slave_config_sdo8), RxPDO 0x1600 = {0x6040, 0x607A, 0x6060} and TxPDO 0x1A00 =
{0x6041, 0x6064, 0x6061} (ecrt_slave_config_pdos), one domain exchanged by LRW, DC with AssignActivate 0x0300 and
SYNC0 every 1 ms (ecrt_slave_config_dc). Exit 0 when every slave reached OP and ran S seconds of cycles with the
expected working counter.
"""
import argparse
import os
import socket
import struct
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "integration"))
import harness  # noqa: E402  (frame exchange on a raw socket)

ETH_P_ECAT = 0x88A4
APRD, APWR, FPRD, FPWR, BRD, BWR, LRW, FRMW = 1, 2, 4, 5, 7, 8, 12, 14
DC_EPOCH_NS = 946684800 * 10**9  # EtherCAT system time counts from 2000-01-01
EC_FIRST_SII_CATEGORY_OFFSET = 0x40  # master/globals.h
EC_SYNC_PAGE_SIZE, EC_FMMU_PAGE_SIZE = 8, 16  # master/globals.h
EC_DC_START_OFFSET = 100_000_000  # master/fsm_slave_config.c: start time = app time + 100 ms
EC_DC_MAX_SYNC_DIFF_NS, EC_DC_SYNC_WAIT_MS = 10000, 5000  # master/fsm_slave_config.c
CYCLE_NS = 1_000_000
RX_PDO = (0x1600, [(0x6040, 0, 16), (0x607A, 0, 32), (0x6060, 0, 8)])
TX_PDO = (0x1A00, [(0x6041, 0, 16), (0x6064, 0, 32), (0x6061, 0, 8)])


class Failed(Exception):
    pass


def app_time():
    return time.time_ns() - DC_EPOCH_NS


class Slave:
    def __init__(self, ring_position):
        self.ring_position = ring_position
        self.station = ring_position + 1  # master/master.c: station address = index + 1
        self.sii = []
        self.fmmu_count = self.sync_count = 0
        self.dc = False
        self.times = (0, 0, 0, 0)
        self.dl_status = 0
        self.delay = 0
        self.syncs = []  # SII SyncM category: (start, length, control, enable)
        self.rx_mbx = self.tx_mbx = None
        self.logical = 0


class Master:
    def __init__(self, iface):
        self.sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETH_P_ECAT))
        self.sock.bind((iface, 0))
        self.idx = 0
        self.slaves = []
        self.active = False  # application active: cyclic datagrams in every frame, 1 ms cycle
        self.next_cycle = 0
        self.domain_size = 0
        self.expected_wkc = 0
        self.wkc_errors = 0
        self.cycles = 0
        self.dc_ref_time = 0
        self.in_op = False

    # -- frames ----------------------------------------------------------------------------------------------
    def _txrx(self, datagrams, timeout=0.05):
        self.idx = (self.idx + 1) & 0xFF
        body = b""
        for i, (cmd, adp, ado, data) in enumerate(datagrams):
            more = 0x8000 if i + 1 < len(datagrams) else 0
            body += struct.pack("<BBHHHH", cmd, self.idx, adp, ado, len(data) | more, 0) + data + b"\x00\x00"
        frame = b"\xff" * 6 + b"\x00\x01\x05\x10\x00\x00" + b"\x88\xa4" + struct.pack("<H", len(body) | 0x1000) + body
        frame += b"\x00" * max(0, 60 - len(frame))
        data = harness.exchange(self.sock, frame, timeout,
                                match=lambda rq, rp: len(rp) >= 28 and rp[17] == rq[17] and bool(rp[6] & 0x02))
        if data is None:
            return None
        return [(d[4], d[5]) for d in harness.parse_datagrams(data)]

    def dg(self, cmd, adp, ado, data):
        """One FSM datagram (master/datagram.c); with the application active, in the cycle's frame beside the
        cyclic datagrams (master/master.c ecrt_master_send). EC_FSM_RETRIES (3) repetitions on a lost frame."""
        if isinstance(data, int):
            data = bytes(data)
        for _ in range(4):
            if self.active:
                wait = self.next_cycle - time.monotonic_ns()
                if wait > 0:
                    time.sleep(wait / 1e9)
                self.next_cycle = max(self.next_cycle + CYCLE_NS, time.monotonic_ns() - 10 * CYCLE_NS)
                cyc = self.cyclic_datagrams()
                r = self._txrx(cyc + [(cmd, adp, ado, data)])
                if r is None:
                    continue
                self.cycles += 1
                if r[2][1] != self.expected_wkc and self.in_op:
                    self.wkc_errors += 1
                return r[-1]
            r = self._txrx([(cmd, adp, ado, data)])
            if r is not None:
                return r[0]
        raise Failed(f"no reply to command {cmd} 0x{adp:04x}:0x{ado:04x}")

    def cyclic_datagrams(self):
        """ecrt_master_sync_reference_clock (FPWR 0x0910, 4 bytes of the application time to the reference
        clock), ecrt_master_sync_slave_clocks (FRMW 0x0910, 4 bytes, from the reference clock to all others) and
        ecrt_domain_queue (LRW of the domain): master/master.c."""
        ref = self.slaves[0].station
        t = app_time()
        return [(FPWR, ref, 0x0910, struct.pack("<I", t & 0xFFFFFFFF)), (FRMW, ref, 0x0910, bytes(4)),
                (LRW, 0x0000, 0x0000, bytes(self.domain_size))]

    def expect(self, r, wkc, what):
        if r[1] != wkc:
            raise Failed(f"{what}: working counter {r[1]}, expected {wkc}")
        return r[0]

    # -- master/fsm_sii.c ------------------------------------------------------------------------------------
    def sii_read(self, s, offset):
        """ec_fsm_sii_start_reading / read_check / read_fetch: write the read command (0x0502: 0x00 0x01 and the
        word address), then read 10 bytes from 0x0502 until the busy bits (0x81 in the high byte) are clear;
        two words at 0x0508."""
        self.expect(self.dg(FPWR, s.station, 0x0502, bytes([0x00, 0x01]) + struct.pack("<H", offset)), 1,
                    "SII read command")
        deadline = time.monotonic() + 1.0
        while True:
            d = self.expect(self.dg(FPRD, s.station, 0x0502, 10), 1, "SII read check")
            if not d[1] & 0x81:
                return d[6:10]
            if time.monotonic() > deadline:
                raise Failed("SII read timeout")

    # -- master/fsm_change.c ---------------------------------------------------------------------------------
    def change_state(self, s, state):
        """ec_fsm_change_state_start: FPWR 0x0120; state_check/state_status: FPRD 0x0130 until the state or the
        error bit; on error FPRD 0x0134 (the code) and acknowledge with the current state | 0x10."""
        self.expect(self.dg(FPWR, s.station, 0x0120, struct.pack("<H", state)), 1, "AL control")
        deadline = time.monotonic() + 5.0
        while True:
            al = struct.unpack("<H", self.expect(self.dg(FPRD, s.station, 0x0130, 2), 1, "AL status"))[0]
            if al & 0x10:
                code = struct.unpack("<H", self.expect(self.dg(FPRD, s.station, 0x0134, 2), 1, "AL code"))[0]
                self.expect(self.dg(FPWR, s.station, 0x0120, struct.pack("<H", (al & 0x0F) | 0x10)), 1, "ack")
                raise Failed(f"slave {s.ring_position}: state 0x{state:x} refused, AL status 0x{al:04x} code "
                             f"0x{code:04x}")
            if al & 0x0F == state:
                return
            if time.monotonic() > deadline:
                raise Failed(f"slave {s.ring_position}: state 0x{state:x} not reached (AL status 0x{al:04x})")

    # -- master/mailbox.c, master/fsm_coe.c ------------------------------------------------------------------
    def mbox_exchange(self, s, payload, mtype=3):
        """ec_slave_mbox_prepare_send: FPWR of the whole receive mailbox (header: length, station address,
        channel/priority 0, type; IgH sets no counter); ec_slave_mbox_prepare_check: FPRD 0x0808 8 bytes until
        SM1's status has the mailbox-full bit (byte 5 bit 3); ec_slave_mbox_prepare_fetch: FPRD of the whole
        send mailbox."""
        start, size = s.rx_mbx
        data = struct.pack("<HHBB", len(payload), s.station, 0, mtype) + payload
        data += bytes(size - len(data))
        self.expect(self.dg(FPWR, s.station, start, data), 1, "mailbox write")
        deadline = time.monotonic() + 1.0
        while True:
            st = self.expect(self.dg(FPRD, s.station, 0x0808, 8), 1, "mailbox check")
            if st[5] & 0x08:
                break
            if time.monotonic() > deadline:
                raise Failed("mailbox response timeout")
        reply = self.expect(self.dg(FPRD, s.station, s.tx_mbx[0], bytes(s.tx_mbx[1])), 1, "mailbox fetch")
        n, _addr, _ch, typ = struct.unpack_from("<HHBB", reply)
        return typ & 0x0F, reply[6:6 + n]

    def sdo_upload(self, s, index, sub):
        """ec_fsm_coe_prepare_up: CoE SDO request, initiate upload (0x40), index, subindex, 4 zero bytes."""
        typ, r = self.mbox_exchange(s, struct.pack("<HBHB", 0x2 << 12, 0x2 << 5, index, sub) + bytes(4))
        if typ != 3 or r[2] >> 5 != 2:
            raise Failed(f"upload 0x{index:04x}:{sub:02x}: {r.hex()}")
        if r[2] & 0x02:  # expedited
            return r[6:6 + (4 - ((r[2] >> 2) & 3) if r[2] & 0x01 else 4)]
        size = struct.unpack_from("<I", r, 6)[0]
        return r[10:10 + size]

    def sdo_download(self, s, index, sub, value):
        """ec_fsm_coe_prepare_down_start, expedited (up to 4 bytes): 0x23 | (4 - size) << 2, data padded."""
        cmd = 0x3 | (4 - len(value)) << 2 | 0x1 << 5
        typ, r = self.mbox_exchange(s, struct.pack("<HBHB", 0x2 << 12, cmd, index, sub) + value
                                    + bytes(4 - len(value)))
        if typ != 3 or r[2] != 0x60:
            raise Failed(f"download 0x{index:04x}:{sub:02x}: {r.hex()}")

    # -- master/fsm_master.c ---------------------------------------------------------------------------------
    def scan(self):
        # ec_fsm_master_state_broadcast: BRD 0x0130 counts the responding slaves.
        n = self.dg(BRD, 0, 0x0130, 2)[1]
        if n == 0:
            raise Failed("no slaves")
        self.slaves = [Slave(i) for i in range(n)]
        # ec_fsm_master_enter_dc_read_old_times: APRD 0x0900 16 bytes of each slave.
        for s in self.slaves:
            self.dg(APRD, (-s.ring_position) & 0xFFFF, 0x0900, 16)
        # ec_fsm_master_enter_clear_addresses: BWR 0x0010 = 0; ec_fsm_master_enter_dc_measure_delays: BWR 0x0900.
        self.expect(self.dg(BWR, 0, 0x0010, bytes(2)), n, "clear station addresses")
        self.expect(self.dg(BWR, 0, 0x0900, 1), n, "latch receive times")
        for s in self.slaves:
            self.scan_slave(s)
        self.calc_delays()
        self.write_system_times()

    def scan_slave(self, s):
        """master/fsm_slave_scan.c, in its order."""
        self.expect(self.dg(APWR, (-s.ring_position) & 0xFFFF, 0x0010, struct.pack("<H", s.station)), 1,
                    "station address")
        self.expect(self.dg(FPRD, s.station, 0x0130, 2), 1, "AL state")
        base = self.expect(self.dg(FPRD, s.station, 0x0000, 12), 1, "base data")
        s.fmmu_count, s.sync_count = base[4], base[5]
        if base[8] & 0x04:  # DC supported: ec_fsm_slave_scan_state_dc_cap, dc_times
            s.dc = self.dg(FPRD, s.station, 0x0910, 8 if base[8] & 0x08 else 4)[1] == 1
            s.times = struct.unpack("<4I", self.expect(self.dg(FPRD, s.station, 0x0900, 16), 1, "DC times"))
        s.dl_status = struct.unpack("<H", self.expect(self.dg(FPRD, s.station, 0x0110, 2), 1, "DL status"))[0]
        # ec_fsm_slave_scan_state_sii_size: category headers from word 0x40 to the 0xFFFF end marker.
        off = EC_FIRST_SII_CATEGORY_OFFSET
        while True:
            cat_type, cat_size = struct.unpack("<HH", self.sii_read(s, off))
            if cat_type == 0xFFFF:
                break
            off += 2 + cat_size
            if off >= 0x4000:
                raise Failed("SII without end marker")
        nwords = off + 1
        # ec_fsm_slave_scan_state_sii_data: every word, two at a time.
        words = bytearray()
        for o in range(0, nwords, 2):
            words += self.sii_read(s, o)
        s.sii = bytes(words[:2 * nwords])
        w = lambda i: struct.unpack_from("<H", s.sii, 2 * i)[0]  # noqa: E731
        # SyncM category (0x29): the mailbox and process-data SMs' defaults.
        o = EC_FIRST_SII_CATEGORY_OFFSET
        while w(o) != 0xFFFF:
            t, size = w(o) & 0x7FFF, w(o + 1)
            if t == 0x29:
                for k in range(size * 2 // 8):
                    s.syncs.append(struct.unpack_from("<HHBBBB", s.sii, 2 * (o + 2) + 8 * k))
            o += 2 + size
        s.rx_mbx, s.tx_mbx = (w(0x18), w(0x19)), (w(0x1A), w(0x1B))
        if not w(0x1C) & 0x04:
            raise Failed("no CoE")
        # ec_fsm_slave_scan_enter_preop: a slave in INIT is configured to PREOP first.
        al = self.expect(self.dg(FPRD, s.station, 0x0130, 2), 1, "AL state")[0] & 0x0F
        if al not in (2, 4, 8):
            self.config_to_preop(s)
        # ec_fsm_slave_scan_enter_pdos -> master/fsm_pdo.c reading: assignment 0x1C12/0x1C13, each PDO's mapping.
        for sm_assign in (0x1C12, 0x1C13):
            count = self.sdo_upload(s, sm_assign, 0)[0]
            for k in range(1, count + 1):
                pdo = struct.unpack("<H", self.sdo_upload(s, sm_assign, k)[:2])[0]
                entries = self.sdo_upload(s, pdo, 0)[0]
                for e in range(1, entries + 1):
                    self.sdo_upload(s, pdo, e)

    def calc_delays(self):
        """master/master.c ec_master_calc_dc / ec_slave_calc_port_delays for a line: each slave's round trip
        behind port 1 from the receive times latched by the BWR 0x0900."""
        prev_delay = prev_rt = 0
        for k, s in enumerate(self.slaves):
            rt = (s.times[1] - s.times[0]) & 0xFFFFFFFF if s.dl_status & (1 << 11) else 0
            s.delay = 0 if k == 0 else prev_delay + (prev_rt - rt) // 2
            prev_delay, prev_rt = s.delay, rt

    def write_system_times(self):
        """ec_fsm_master_enter_write_system_times / state_dc_read_offset: FPRD 0x0910 28 bytes (system time,
        offset, delay); FPWR 0x0920 12 bytes (the new offset: application time - system time + old offset, and
        the delay); ec_fsm_master_state_dc_write_offset: FPWR 0x0930 = 0x1000 resets the filter."""
        self.dc_ref_time = app_time()
        for s in self.slaves:
            if not s.dc:
                continue
            sent = app_time()
            d = self.expect(self.dg(FPRD, s.station, 0x0910, 28), 1, "DC read offset")
            system_time, old_offset = struct.unpack_from("<Q", d, 0)[0], struct.unpack_from("<Q", d, 16)[0]
            diff = sent - system_time
            new_offset = old_offset if -1000 < diff < 1000 else (diff + old_offset) & 0xFFFFFFFFFFFFFFFF
            self.expect(self.dg(FPWR, s.station, 0x0920, struct.pack("<QI", new_offset, s.delay & 0xFFFFFFFF)), 1,
                        "DC offset")
            self.expect(self.dg(FPWR, s.station, 0x0930, struct.pack("<H", 0x1000)), 1, "DC filter reset")

    # -- master/fsm_slave_config.c ---------------------------------------------------------------------------
    def config_to_preop(self, s):
        """INIT, clear the SMs (FPWR 0x0800, 8 bytes each), clear the DC assignment (FPWR 0x0980), the mailbox
        SMs from the SII's SyncM category (FPWR 0x0800, every SII SM; those past SM1 zero), PREOP."""
        self.change_state(s, 1)
        self.expect(self.dg(FPWR, s.station, 0x0800, EC_SYNC_PAGE_SIZE * s.sync_count), 1, "clear SMs")
        self.expect(self.dg(FPWR, s.station, 0x0980, 2), 1, "clear DC assign")
        if len(s.syncs) >= 2:
            pages = bytearray(EC_SYNC_PAGE_SIZE * len(s.syncs))
            for i in range(2):  # ec_sync_page: start, length, control, status 0, enable, 0
                start, length, control, _st, enable, _t = s.syncs[i]
                struct.pack_into("<HHBBBB", pages, 8 * i, start, length, control, 0, enable & 1, 0)
            self.expect(self.dg(FPWR, s.station, 0x0800, bytes(pages)), 1, "mailbox SMs")
        self.change_state(s, 2)

    def configure(self, s):
        """The rest of fsm_slave_config.c for an application's slave configuration, from PREOP: SDO
        configuration, PDO mapping (fsm_pdo.c / fsm_pdo_entry.c: count 0, each entry, count), process-data SMs,
        FMMUs, DC cycle times, the synchrony check on 0x092C, start time, AssignActivate, SAFEOP."""
        self.sdo_download(s, 0x6060, 0, struct.pack("<b", 8))  # ecrt_slave_config_sdo8(sc, 0x6060, 0, 8)
        sizes = []
        for pdo, entries in (RX_PDO, TX_PDO):
            self.sdo_download(s, pdo, 0, b"\x00")
            for k, (index, sub, bits) in enumerate(entries, 1):
                self.sdo_download(s, pdo, k, struct.pack("<I", index << 16 | sub << 8 | bits))
            self.sdo_download(s, pdo, 0, bytes([len(entries)]))
            sizes.append(sum(b for _i, _s, b in entries) // 8)
        # The assignment (0x1C12/0x1C13) already holds these PDOs: fsm_pdo.c skips writing it when equal.
        out_len, in_len = sizes
        pages = b""
        for i, length in ((2, out_len), (3, in_len)):  # ec_fsm_slave_config_enter_pdo_sync
            start, _l, control, _st, _en, _t = s.syncs[i]
            pages += struct.pack("<HHBBBB", start, length, control, 0, 1, 0)
        self.expect(self.dg(FPWR, s.station, 0x0810, pages), 1, "PDO SMs")
        fm = bytearray(EC_FMMU_PAGE_SIZE * s.fmmu_count)  # ec_fsm_slave_config_enter_fmmu, fmmu_config.c
        struct.pack_into("<IHBBHBBBxxx", fm, 0, s.logical, out_len, 0, 7, s.syncs[2][0], 0, 2, 1)
        struct.pack_into("<IHBBHBBBxxx", fm, 16, s.logical + out_len, in_len, 0, 7, s.syncs[3][0], 0, 1, 1)
        self.expect(self.dg(FPWR, s.station, 0x0600, bytes(fm)), 1, "FMMUs")
        # ec_fsm_slave_config_enter_dc_cycle: cycle times; state_dc_sync_check: 0x092C until below 10 us (5 s).
        self.expect(self.dg(FPWR, s.station, 0x09A0, struct.pack("<II", CYCLE_NS, 0)), 1, "DC cycle")
        deadline = time.monotonic() + EC_DC_SYNC_WAIT_MS / 1000
        while time.monotonic() < deadline:
            diff = struct.unpack("<I", self.expect(self.dg(FPRD, s.station, 0x092C, 4), 1, "DC sync check"))[0]
            if diff & 0x7FFFFFFF <= EC_DC_MAX_SYNC_DIFF_NS:
                break
        start = app_time() + EC_DC_START_OFFSET  # state_dc_sync_check: in phase with dc_ref_time
        start += CYCLE_NS - (start - self.dc_ref_time) % CYCLE_NS
        self.expect(self.dg(FPWR, s.station, 0x0990, struct.pack("<Q", start)), 1, "DC start time")
        self.expect(self.dg(FPWR, s.station, 0x0980, struct.pack("<H", 0x0300)), 1, "DC AssignActivate")
        self.change_state(s, 4)

    def run(self, seconds):
        self.scan()
        # ecrt_master_activate: the application's domain (each slave's outputs then inputs), its cycle starts.
        logical = 0
        for s in self.slaves:
            s.logical = logical
            logical += 14
        self.domain_size = logical
        self.expected_wkc = 3 * len(self.slaves)
        self.in_op = False
        self.active = True
        self.next_cycle = time.monotonic_ns()
        for s in self.slaves:  # master/fsm_master.c: reconfigures every slave (fsm_slave_config from INIT)
            self.config_to_preop(s)
            self.configure(s)
        for s in self.slaves:
            self.change_state(s, 8)
        self.in_op = True
        end = time.monotonic() + seconds
        while time.monotonic() < end:  # the cycle with IgH's idle FSM datagram: BRD 0x0130 (state of the bus)
            self.expect(self.dg(BRD, 0, 0x0130, 2), len(self.slaves), "bus state")
        return self.wkc_errors


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("iface")
    ap.add_argument("--seconds", type=float, default=1.0)
    a = ap.parse_args()
    m = Master(a.iface)
    try:
        errors = m.run(a.seconds)
    except Failed as e:
        print(f"igh_master: {e}", file=sys.stderr)
        return 1
    print(f"{len(m.slaves)} slaves in OP, {m.cycles} cycles, {errors} working-counter errors in OP")
    return 0 if errors == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
