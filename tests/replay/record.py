#!/usr/bin/env python3
"""Records one master's start-up against ecat-slave for the replay corpus (tests/replay/README.md).

    sudo ECAT_SLAVE=build/tools/ecat-slave/ecat-slave ECATCTL=build/tools/ecatctl/ecatctl \
        tests/replay/record.py NAME [--slaves N] [--seconds S] [--master-version TEXT] -- COMMAND ...

COMMAND is the master's command line with {iface} where the master end of the veth pair goes. The slave runs
as harness.Bus starts it (its own namespace, default device, fresh state directory) with the --slaves given;
dumpcap records the master end (the master's frames and the slave's replies) until COMMAND exits, or for
--seconds when it is given (then COMMAND gets SIGINT, as Ctrl-C). Writes corpus/NAME.pcap.gz and the sidecar
corpus/NAME.json the replay starts the slave from; prints the master's output.
"""
import argparse
import datetime
import json
import os
import signal
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "integration"))
import harness  # noqa: E402
import ecatreplay  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("name")
    ap.add_argument("--slaves", type=int, default=1)
    ap.add_argument("--seconds", type=float, default=None, help="stop the master (SIGINT) after this long")
    ap.add_argument("--master-version", default="", help="version or commit of the master, for the README")
    ap.add_argument("--description", default="")
    ap.add_argument("--malformed-requests", action="store_true",
                    help="the master sends malformed frames on purpose (ecat-conform's robustness tests)")
    ap.add_argument("--rt-priority", type=int, default=None,
                    help="run the slave at this real-time priority while recording (a loaded host; not replayed: "
                         "it changes when replies come, not what they say)")
    argv = sys.argv[1:]
    cut = argv.index("--") if "--" in argv else len(argv)
    a = ap.parse_args(argv[:cut])
    cmd = argv[cut + 1:]
    if not cmd:
        ap.error("no master command")
    slave_args = ["--slaves", str(a.slaves)] if a.slaves > 1 else []
    os.makedirs(ecatreplay.CORPUS, exist_ok=True)
    timing_args = ["--rt-priority", str(a.rt_priority)] if a.rt_priority else []
    with harness.Bus(slave_args=slave_args + timing_args) as bus:
        tmp = tempfile.NamedTemporaryFile(suffix=".pcap", delete=False, dir=bus.dir).name
        cap = subprocess.Popen(["dumpcap", "-q", "-P", "-i", bus.iface, "-f", "ether proto 0x88a4", "-w", tmp],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            deadline = time.monotonic() + 10
            while (not os.path.exists(tmp) or os.path.getsize(tmp) < 24) and time.monotonic() < deadline:
                time.sleep(0.05)
            time.sleep(0.5)  # dumpcap writes the header before its filter is attached
            argv = [x.replace("{iface}", bus.iface) for x in cmd]
            stopped = None
            master = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                      start_new_session=True)
            try:
                out, _ = master.communicate(timeout=a.seconds if a.seconds else 120)
            except subprocess.TimeoutExpired:
                if not a.seconds:
                    os.killpg(master.pid, signal.SIGKILL)
                    raise
                stopped = time.time()  # dumpcap's time stamps are wall-clock time
                os.killpg(master.pid, signal.SIGINT)
                try:
                    out, _ = master.communicate(timeout=5)
                except subprocess.TimeoutExpired:
                    os.killpg(master.pid, signal.SIGKILL)
                    out, _ = master.communicate()
            time.sleep(0.3)
        finally:
            cap.send_signal(signal.SIGINT)
            cap.wait(timeout=10)
        print(out)
        frames = ecatreplay.read_pcap(tmp)
        if not frames:
            sys.exit("nothing recorded")
        if stopped is not None:
            # The start-up and the cycles up to the stop: requests sent after it (the master's shut-down) are
            # left out, replies to earlier ones kept.
            kept = set()
            for t, rq, rp in ecatreplay.pair(frames):
                if t <= stopped:
                    kept.add(id(rq))
                    if rp is not None:
                        kept.add(id(rp))
            frames = [(t, fr) for t, fr in frames if id(fr) in kept]
        t0 = frames[0][0]
        frames = [(t - t0, fr) for t, fr in frames]
        pcap = f"{a.name}.pcap.gz"
        ecatreplay.write_pcap(os.path.join(ecatreplay.CORPUS, pcap), frames)
        pairs = ecatreplay.pair(frames)
        side = {
            "pcap": pcap,
            "description": a.description,
            "master_command": [x.replace("{iface}", "IFACE") for x in cmd],
            "master_version": a.master_version,
            "master_exit": master.returncode,
            "seconds": a.seconds,
            "kept": "start-up and cycles until the master was stopped" if stopped is not None else "everything",
            "slave_args": slave_args,
            "recording_slave_timing_args": timing_args,
            "malformed_requests": a.malformed_requests,
            "recorded": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d"),
            "requests": len(pairs),
            "unanswered": sum(1 for p in pairs if p[2] is None),
        }
        with open(os.path.join(ecatreplay.CORPUS, f"{a.name}.json"), "w") as f:
            json.dump(side, f, indent=2)
            f.write("\n")
        print(f"{a.name}: {len(frames)} frames, {len(pairs)} requests, {side['unanswered']} unanswered, "
              f"master exit {master.returncode}")


if __name__ == "__main__":
    main()
