#!/usr/bin/env python3
"""SOEM (through pysoem) against the raw-socket runner `pam-slave`.

A master we did not write drives a line of software PAM-199-P-ETC slaves
over a real network interface (a veth pair in the integration test). The
Rust test `veth::soem_*` builds the files, starts the runner in a network
namespace, runs the phases of this script and checks its exit status; this
script prints what SOEM saw (names, abort codes, working counters) and
exits 1 on the first disagreement.

    soem_interop.py phase1 IFACE ESI.xml EEPROM.bin GOOD.efw BAD_CRC.efw VERSION OLD.efw
    soem_interop.py phase2 IFACE VERSION
    soem_interop.py chain IFACE NAME,NAME,...
    soem_interop.py dc IFACE COUNT
    soem_interop.py twins IFACE SPEC ENI.xml
    soem_interop.py esi_twin IFACE ESI.xml
    soem_interop.py safety IFACE
    soem_interop.py safety_after_power_cycle IFACE
    soem_interop.py board IFACE ESI.xml EEPROM.bin GOOD.efw BAD_CRC.efw BOOT_OUT BOOT_IN
    soem_interop.py board_after_restart IFACE VERSION
    soem_interop.py servo402 IFACE
    soem_interop.py corpus IFACE SPEC DRIVE

phase1: discovery, SDO, SDO Information, complete access, SII, state
machine, SM watchdog, 1000 cycles, an ended session followed by a second
one, FoE refusals (wrong password, corrupt image), the owner's new FoE
password set with a plain foe_write of foe-password.txt (the factory
password refused afterwards), the slave's anti-rollback (OLD.efw, older
than the running firmware, refused; accepted under a file name ending in
.downgrade.efw, the owner's consent) and a good FoE download in BOOT,
then BOOT -> INIT.
phase2 (after the runner restarted, i.e. a power cycle): the new firmware
version in 0x100A on the updated slave, and OP again.
chain: a line spread over several runners (`pam-slave --forward`): SOEM
finds the slaves named, in that order, with SOEM's station addresses,
reads an SDO from each, brings them all to OP and runs 200 cycles with
its expected working counter.
dc: SOEM's Distributed Clocks: config_dc (receive times, offsets,
delays), dcsync0 (SYNC0 every 1 ms, shifted 250 us) on every slave, OP with SOEM's
process data cycle (which distributes the reference time), then every
slave's system time difference (0x092C), its sync mode and cycle in
0x1C32, SYNC0 running (0x0990 advancing by whole cycles); a SYNC0 cycle
of 10 us is refused at SAFE-OP with 0x0035.
twins: a line built from an ENI (`pam-slave --eni`): SOEM finds every
slave with the identity (vendor, product, revision), the name and the
output/input sizes SPEC lists (`name|vendor|product|revision|out|in` per
slave, `;`-separated, taken from the real devices' SII dumps by the Rust
test), brings the line to OP, runs 100 cycles at the expected working
counter and sees the counter twin's inputs move. Before SAFE-OP it
executes the ENI's CoE init commands of the PS transition through SOEM's
SDO download, as a master working from the ENI does; afterwards their
values read back (a PAM parameter, a CoE twin's setting) and the image
sizes SOEM derives from the written assignments are the ENI's.
esi_twin: a twin of a device with CoE built from its ESI alone
(`pam-slave --esi ESI.xml --inputs loopback`): SOEM finds the ESI's
identity and type name, SDO Information lists exactly the ESI's objects
with the ESI's names, SDO reads of 0x1018 give the identity, the process
image has the ESI's PDO sizes, the twin reaches OP and its inputs loop its
outputs back.
safety (one PAM): with no RxPDO assigned, ENABLE and a command value
written over SDO in OP drive no current; with FUNCTION = IND in OP,
DEFAULT and LOADBACK that would change FUNCTION are refused with
0x08000022 and FUNCTION stays; SAVE with FUNCTION = IND.
safety_after_power_cycle: FUNCTION = IND came back with its PDO set
(0x1601/0x1A01) and OP is reached without rewriting the assignment.
board: one IO8 whose firmware runs in QEMU (examples/board/qemu, the
LAN9252 reached over the emulated UART through board-bridge): identity
and name, SDO and the aborts SOEM decodes, SDO Information against the
ESI, the SII, the state machine, 1000 cycles with the outputs looped
back to the inputs, the SM watchdog to SAFE-OP and back, and FoE in BOOT
(a corrupt image refused, a good one written, BOOT -> INIT). BOOT_OUT and
BOOT_IN are the bootstrap mailbox as `start:length` (hex).
board_after_restart (after QEMU restarted on the same bridge, i.e. a
board reset with its flash kept): 0x100A is VERSION, OP and 100 cycles.
corpus SPEC DRIVE: twins of vendors' devices from the ESI corpus (names
and identities per SPEC, as in twins), OP, and the CiA 402 drive at
position DRIVE given a mapping of SOEM's own in its configuration hook,
DC SYNC0, Operation enabled in CSP and a ramp the position follows.
servo402 (one CiA 402 servo drive): SOEM writes a PDO mapping of its own
in its configuration hook (each refusal on the way checked: 0x06010003,
0x06040041, 0x06040043), the assignment and the mode (0x6060 = 8, CSP)
in PRE-OP, the images sized from the written mapping; configures DC (config_dc, SYNC0
every 1 ms), reaches OP DC-synchronous, walks the drive's state machine
to Operation enabled (0x0006, 0x0007, 0x000F, the target at the actual
position first), runs a ramp of target positions and checks that the
position follows (following error within its window, the position on
the target after the ramp, no fault), then a quick stop to Switch on
disabled and the drive disabled before leaving OP.
"""

import struct
import sys
import time
import xml.etree.ElementTree as ET

import pysoem

PRODUCT = 0x00C7_03F3
VENDOR = 0x0000_05AE
NAME = "PAM-199-P-ETC"
FAILURES = []


def log(msg):
    print(msg, flush=True)


def check(ok, what):
    log(("ok    " if ok else "FAIL  ") + what)
    if not ok:
        FAILURES.append(what)
    return ok


def open_master(iface):
    m = pysoem.Master()
    m.open(iface)
    n = m.config_init()
    return m, n


def al_status_code(slave):
    return struct.unpack("<H", slave._fprd(0x0134, 2, 20000))[0]


def al_status(slave):
    return struct.unpack("<H", slave._fprd(0x0130, 2, 20000))[0]


def request_state(m, slave, state, wait_s=2.0):
    """Requests `state` and waits until the slave reached it or refused
    it. With STATE_ACK the error bit must clear too; without, an error
    counts only once the status changed from what it was before the
    request (a firmware that takes a few milliseconds, as one in QEMU,
    still shows the old error at first)."""
    before = al_status(slave)
    slave.state = state
    slave.write_state()
    deadline = time.monotonic() + wait_s
    st = before
    while time.monotonic() < deadline:
        st = al_status(slave)
        reached = st & 0x0F == state & 0x0F
        if state & pysoem.STATE_ACK:
            if reached and not st & 0x10:
                break
        elif reached or (st & 0x10 and st != before):
            break
        time.sleep(0.002)
    return st, al_status_code(slave)


def abort_of(fn):
    try:
        fn()
    except pysoem.SdoError as e:
        return e.abort_code
    return None


# SOEM's frame timeouts are compiled in (2-6 ms per frame). On a loaded CI
# machine the runner process may not be scheduled that fast; what is
# checked is the protocol, not the machine's speed, so the receive timeout
# of the cycle is generous and the SM watchdog is lengthened wherever the
# test does not examine it.
RECEIVE_TIMEOUT_US = 200_000
LONG_WATCHDOG_MS = 5000


def fixed_mapping_by_complete_access(s, where):
    """A fixed mapping (0x1A00, every entry read-only) by complete access:
    its own values written back are acknowledged, a changed one is refused
    read-only (0x06010002) and the mapping stays."""
    held = s.sdo_read(0x1A00, 0, 256, ca=True)
    s.sdo_write(0x1A00, 0, held, ca=True)
    changed = bytearray(held)
    changed[2] ^= 0x08  # the first mapped entry's bit length
    code = abort_of(lambda: s.sdo_write(0x1A00, 0, bytes(changed), ca=True))
    check(code == 0x06010002, f"{where}: a changed fixed mapping refused ({code and hex(code)})")
    check(s.sdo_read(0x1A00, 0, 256, ca=True) == held,
          f"{where}: 0x1A00 unchanged, its own values written back acknowledged")


def cycles(m, n, period_s=0.002):
    """n process-data cycles; returns the list of working counters."""
    wkcs = []
    for _ in range(n):
        m.send_processdata()
        wkcs.append(m.receive_processdata(RECEIVE_TIMEOUT_US))
        time.sleep(period_s)
    return wkcs


def set_sm_watchdog(m, ms):
    """SOEM's set_watchdog (register reads and writes with SOEM's
    compiled-in 2 ms timeout). A frame lost to a scheduling delay on a
    loaded machine (WkcError) is tried again, up to 3 times, as a master
    retries a lost frame; the log says so."""
    for i, s in enumerate(m.slaves):
        for attempt in range(3):
            try:
                s.set_watchdog("processdata", ms)
                break
            except pysoem.WkcError:
                log(f"      slave {i + 1}: set_watchdog lost a frame (attempt {attempt + 1}), again")
                if attempt == 2:
                    raise
                time.sleep(0.01)


def drain_mailbox(s):
    """Reads away whatever answer of an earlier exchange still waits in
    the slave's SM1 (a reply SOEM gave up on after its compiled-in 2 ms
    timeout): it would put the next exchange out of step."""
    for _ in range(4):
        try:
            if not s.mbx_receive():
                return
        except Exception:
            return


def foe_write(s, name, password, data):
    """SOEM's foe_write, after draining a stale answer. A frame lost to a
    scheduling delay (EC_NOFRAME, -1: no answer within SOEM's compiled-in
    2 ms) or an exchange put out of step by a late answer (-3: a packet of
    the wrong kind) is retried once with a fresh write request after the
    pending answers are drained, as a user would; the log says so. A
    refusal by the slave (-5, an FoE error packet) is never retried."""
    drain_mailbox(s)
    r = s.foe_write(name, password, data, 10_000_000)
    if r in (-1, -3):
        log(f"      foe_write returned {r} (a late or lost frame); retrying once")
        time.sleep(0.1)
        drain_mailbox(s)
        r = s.foe_write(name, password, data, 10_000_000)
    return r


def to_op(m):
    """SAFE-OP, then OP with outputs flowing (the SM watchdog is armed)."""
    m.state = pysoem.SAFEOP_STATE
    m.write_state()
    m.state_check(pysoem.SAFEOP_STATE, 2_000_000)
    m.state = pysoem.OP_STATE
    m.write_state()
    for _ in range(500):
        cycles(m, 1)
        if m.state_check(pysoem.OP_STATE, 2000) == pysoem.OP_STATE:
            return True
    return False


def esi_object_indices(path):
    root = ET.parse(path).getroot()
    return [
        int(o.find("Index").text.replace("#x", "0x"), 16)
        for o in root.iter("Object")
    ]


def phase1(iface, esi, sii_path, good_efw, bad_efw, version, old_efw):
    m, n = open_master(iface)
    check(n == 8, f"SOEM config_init found {n} slaves (8 expected)")
    for i, s in enumerate(m.slaves):
        log(f"      slave {i}: vendor {s.man:#010x} product {s.id:#010x} revision {s.rev} name {s.name!r}")
    check(all(s.man == VENDOR and s.id == PRODUCT and s.rev == 7 for s in m.slaves),
          "identity of every slave (vendor 0x05AE, product 0x00C703F3, revision 7)")
    check(all(s.name == NAME for s in m.slaves), f"every slave is named {NAME!r}")
    s = m.slaves[0]

    # --- SDO upload/download and the abort codes SOEM reports
    s.sdo_write(0x800D, 2, struct.pack("<H", 2000))
    check(struct.unpack("<H", s.sdo_read(0x800D, 2))[0] == 2000, "SDO download/upload 0x800D:02 CURRENT = 2000")
    aborts = {
        "out of range 0x800D:02 = 5000": (lambda: s.sdo_write(0x800D, 2, struct.pack("<H", 5000)), 0x06090031),
        "read-only 0x1018:01": (lambda: s.sdo_write(0x1018, 1, struct.pack("<I", 1)), 0x06010002),
        "unknown object 0x1234": (lambda: s.sdo_read(0x1234, 0), 0x06020000),
        "unknown subindex 0x1008:07": (lambda: s.sdo_read(0x1008, 7), 0x06090011),
        "padding 0x6000:02": (lambda: s.sdo_read(0x6000, 2), 0x06010000),
    }
    for what, (fn, want) in aborts.items():
        got = abort_of(fn)
        check(got == want, f"abort for {what}: SOEM got {got if got is None else hex(got)}, want {want:#010x}")
    check(struct.unpack("<H", s.sdo_read(0x800D, 2))[0] == 2000, "a refused write leaves 0x800D:02 at 2000")
    name = s.sdo_read(0x1008, 0).decode()
    check(name == NAME, f"0x1008 DEVICE NAME (segmented by size) = {name!r}")

    # --- SDO Information: object list equal to the ESI
    od = s.od
    live = [o.index for o in od]
    want = esi_object_indices(esi)
    check(live == want, f"SDO Information lists {len(live)} objects, the ESI {len(want)}: equal")
    by_index = {o.index: o for o in od}
    o8006 = by_index.get(0x8006)
    check(o8006 is not None and len(o8006.entries) == 43, "SDO Information: 0x8006 has subindex 0..42")
    o6000 = by_index.get(0x6000)
    if o6000 is not None:
        pad = o6000.entries[2]
        check(pad.data_type == 0 and pad.obj_access == 0 and pad.bit_length == 7,
              f"0x6000:02 padding: type {pad.data_type}, access {pad.obj_access:#x}, {pad.bit_length} bits")

    # --- complete access of 0x8006
    img = s.sdo_read(0x8006, 0, 256, ca=True)
    check(len(img) == 86 and img[0] == 42, f"complete access upload of 0x8006: {len(img)} bytes")
    new = bytearray(img)
    for i in range(42):
        new[2 + 2 * i: 4 + 2 * i] = struct.pack("<h", (i - 21) * 300)
    s.sdo_write(0x8006, 0, bytes(new), ca=True)
    back = s.sdo_read(0x8006, 0, 256, ca=True)
    check(back == bytes(new), "complete access download of 0x8006 reads back")
    check(struct.unpack("<h", s.sdo_read(0x8006, 0x2A))[0] == 20 * 300, "0x8006:2A after the complete download")

    # --- the SII through SOEM equals `esi sii`
    want_sii = open(sii_path, "rb").read()
    got = bytearray()
    for word in range(0, len(want_sii) // 2, 2):
        got += s.eeprom_read(word)
    check(bytes(got) == want_sii, f"SII read by SOEM ({len(got)} bytes) equals `esi sii`")

    # --- state machine: INIT -> OP refused with 0x0011
    st, code = request_state(m, s, pysoem.INIT_STATE)
    st, code = request_state(m, s, pysoem.OP_STATE)
    check(st == 0x11 and code == 0x0011, f"INIT->OP refused: AL status {st:#06x}, code {code:#06x}")
    st, code = request_state(m, s, pysoem.INIT_STATE | pysoem.STATE_ACK)
    check(st == 0x01, f"acknowledged back to INIT: {st:#06x}")
    st, code = request_state(m, s, pysoem.PREOP_STATE)
    check(st == 0x02, f"INIT->PRE-OP: {st:#06x}")

    # --- process data: config_map, OP, 1000 cycles with the expected WKC
    m.read_state()
    set_sm_watchdog(m, LONG_WATCHDOG_MS)
    size = m.config_map()
    log(f"      config_map: I/O map {size} bytes, expected WKC {m.expected_wkc}")
    check(m.expected_wkc == 3 * 8, f"expected working counter {m.expected_wkc} (3 per slave)")
    check(to_op(m), "all 8 slaves in OP")
    wkcs = cycles(m, 1000, 0.0005)
    bad = [w for w in wkcs if w != m.expected_wkc]
    log(f"      1000 cycles: working counters min {min(wkcs)} max {max(wkcs)}, {len(bad)} unexpected")
    check(not bad, "1000 cycles, every working counter as expected")
    fixed_mapping_by_complete_access(s, "OP")

    # --- SM watchdog (back to its 100 ms default): stop the outputs,
    # SAFE-OP + 0x001B, back to OP
    set_sm_watchdog(m, 100)
    cycles(m, 5)
    time.sleep(0.3)
    st, code = al_status(s), al_status_code(s)
    check(st == 0x14 and code == 0x001B, f"outputs stopped 300 ms: AL status {st:#06x}, code {code:#06x}")
    s.state = pysoem.SAFEOP_STATE | pysoem.STATE_ACK
    s.write_state()
    cycles(m, 20)
    st, code = request_state(m, s, pysoem.OP_STATE)
    for _ in range(200):
        cycles(m, 1)
        st = al_status(s)
        if st == 0x08:
            break
    check(st == 0x08, f"acknowledged, outputs flowing, OP again: {st:#06x}")
    set_sm_watchdog(m, LONG_WATCHDOG_MS)

    # --- the session ends in OP without a goodbye; the next one starts
    m.close()
    m, n = open_master(iface)
    check(n == 8, "second session finds the 8 slaves")
    set_sm_watchdog(m, LONG_WATCHDOG_MS)
    try:
        m.config_map()
        ok = True
    except pysoem.ConfigMapError as e:
        ok = False
        log(f"      config_map error list: {e.error_list}")
    check(ok, "second session: config_map without errors (no stale emergencies)")
    check(to_op(m), "second session: OP")
    cycles(m, 50)

    # --- FoE in BOOT (slave 8, the last): refusals, then a good image.
    # As SOEM's firmware-update example does it: a session of its own
    # (config_init, no config_map), INIT, SM0/SM1 set to the bootstrap
    # mailbox of the SII, BOOT, foe_write.
    m.close()
    m, n = open_master(iface)
    s = m.slaves[7]
    m.state = pysoem.INIT_STATE
    m.write_state()
    m.state_check(pysoem.INIT_STATE, 2_000_000)
    s.amend_mbx("out", 0x1000, 1024)
    s.amend_mbx("in", 0x1400, 1024)
    st, code = request_state(m, s, pysoem.BOOT_STATE)
    check(st == 0x03, f"INIT->BOOT with the bootstrap mailbox: {st:#06x} code {code:#06x}")
    good = open(good_efw, "rb").read()
    bad = open(bad_efw, "rb").read()
    r = foe_write(s, "pam-199-p-etc.efw", 0x1234, good)
    log(f"      foe_write with a wrong password returned {r}")
    check(r == -5, "wrong password refused with an FoE error (SOEM -5)")
    r = foe_write(s, "pam-199-p-etc.efw", 0, bad)
    log(f"      foe_write of a corrupt image returned {r}")
    check(r == -5, "corrupt image refused with an FoE error (SOEM -5)")
    # The owner's password: a plain FoE download with the current one.
    r = foe_write(s, "foe-password.txt", 0, b"C0FFEE42\n")
    log(f"      foe_write of foe-password.txt returned {r}")
    check(r > 0, "new FoE password set with foe_write")
    r = foe_write(s, "pam-199-p-etc.efw", 0, good)
    log(f"      foe_write with the factory password returned {r}")
    check(r == -5, "the factory password is refused once the owner set one (SOEM -5)")
    password = 0xC0FFEE42
    # Anti-rollback in the slave: 9 is older than the running 10.
    old = open(old_efw, "rb").read()
    r = foe_write(s, "pam-199-p-etc.efw", password, old)
    log(f"      foe_write of an older image returned {r}")
    check(r == -5, "older image refused by the slave (anti-rollback 0x8002, SOEM -5)")
    r = foe_write(s, "pam-199-p-etc.downgrade.efw", password, old)
    log(f"      foe_write of the older image as .downgrade.efw returned {r}")
    check(r > 0, "the same older image accepted with the owner's consent (.downgrade.efw)")
    t = time.monotonic()
    r = foe_write(s, "pam-199-p-etc.efw", password, good)
    dt = time.monotonic() - t
    log(f"      foe_write of {len(good)} bytes returned {r} in {dt:.3f} s")
    check(r > 0, "good image written")
    st, code = request_state(m, s, pysoem.INIT_STATE)
    check(st == 0x01, f"BOOT->INIT (image handed to the bootloader): {st:#06x} code {code:#06x}")
    m.close()


def phase2(iface, version):
    m, n = open_master(iface)
    check(n == 8, f"after the power cycle SOEM finds {n} slaves")
    set_sm_watchdog(m, LONG_WATCHDOG_MS)
    v = [s.sdo_read(0x100A, 0).decode() for s in m.slaves]
    log(f"      0x100A per slave: {v}")
    check(v[7] == version, f"slave 8 runs the new firmware {version!r}")
    check(all(x == "10" for x in v[:7]), "the other slaves still run 10")
    m.config_map()
    check(to_op(m), "OP after the update")
    wkcs = cycles(m, 100, 0.0005)
    check(all(w == m.expected_wkc for w in wkcs), "100 cycles after the update")
    m.close()


def chain(iface, names):
    want = names.split(",")
    m, n = open_master(iface)
    got = [s.name for s in m.slaves]
    log(f"      SOEM finds {n} slaves: {got}")
    check(got == want, f"the line in order: {want}")
    addrs = [struct.unpack("<H", s._fprd(0x0010, 2, 20000))[0] for s in m.slaves]
    check(addrs == [0x1001 + i for i in range(n)], f"station addresses {[hex(a) for a in addrs]}")
    set_sm_watchdog(m, LONG_WATCHDOG_MS)
    products = [s.sdo_read(0x1018, 2) for s in m.slaves]
    check(all(len(p) == 4 for p in products), "0x1018:02 read over SDO from every runner's slaves")
    size = m.config_map()
    log(f"      config_map: I/O map {size} bytes, expected WKC {m.expected_wkc}")
    check(to_op(m), "every slave of every runner in OP")
    wkcs = cycles(m, 200, 0.0005)
    bad = [w for w in wkcs if w != m.expected_wkc]
    check(not bad, f"200 cycles with WKC {m.expected_wkc} ({len(bad)} others: {bad[:5]})")
    m.close()


def dc_difference(v):
    """0x092C: bit 31 set = the local copy is smaller, bits 30..0 = ns."""
    return -(v & 0x7FFFFFFF) if v & 0x80000000 else v


def dc(iface, count):
    count = int(count)
    m, n = open_master(iface)
    check(n == count, f"SOEM finds {n} slaves ({count} expected)")
    has_dc = m.config_dc()
    check(bool(has_dc), f"config_dc: the line has DC ({has_dc})")
    delays = [struct.unpack("<I", s._fprd(0x0928, 4, 20000))[0] for s in m.slaves]
    log(f"      transmission delays SOEM wrote (0x0928): {delays} ns")
    check(delays[0] == 0 and all(b > a for a, b in zip(delays, delays[1:])),
          "delays grow along the line from 0 at the reference")
    set_sm_watchdog(m, LONG_WATCHDOG_MS)
    # SYNC0 in PRE-OP, before config_map requests SAFE-OP (as SOEM's
    # PO2SO hooks do it): the slaves check it at PRE-OP -> SAFE-OP.
    cycle, shift = 1_000_000, 250_000
    for s in m.slaves:
        s.dc_sync(1, cycle, shift)
    m.config_map()
    check(to_op(m), f"all {count} slaves in OP, DC-synchronous (SYNC0 every {cycle} ns)")
    wkcs = cycles(m, 500, 0.001)
    bad = [w for w in wkcs if w != m.expected_wkc]
    check(not bad, f"500 cycles with WKC {m.expected_wkc} ({len(bad)} others)")
    diffs = [dc_difference(struct.unpack("<I", s._fprd(0x092C, 4, 20000))[0]) for s in m.slaves]
    log(f"      system time differences (0x092C) after 500 cycles: {diffs} ns")
    check(all(abs(d) <= 1000 for d in diffs), "every slave within 1 us of the reference")
    modes = [struct.unpack("<H", s.sdo_read(0x1C32, 1))[0] for s in m.slaves]
    cycles_od = [struct.unpack("<I", s.sdo_read(0x1C32, 2))[0] for s in m.slaves]
    check(all(x == 2 for x in modes), f"0x1C32:01 sync mode DC SYNC0 (2) on every slave: {modes}")
    check(all(c == cycle for c in cycles_od), f"0x1C32:02 cycle time {cycle} ns: {cycles_od}")
    s = m.slaves[0]
    n1 = struct.unpack("<Q", s._fprd(0x0990, 8, 20000))[0]
    time.sleep(0.05)
    cycles(m, 5, 0.001)
    n2 = struct.unpack("<Q", s._fprd(0x0990, 8, 20000))[0]
    log(f"      next SYNC0 pulse (0x0990): {n1} then {n2}")
    check(n2 > n1 and (n2 - n1) % cycle == 0, "SYNC0 runs: the next pulse moved on by whole cycles")
    check(n1 % cycle == shift and n2 % cycle == shift,
          f"SYNC0 pulses {shift} ns after each cycle boundary (SOEM's shift): {n1 % cycle}, {n2 % cycle}")
    # A cycle the firmware cannot run: refused at SAFE-OP with 0x0035.
    m.state = pysoem.INIT_STATE
    m.write_state()
    m.state_check(pysoem.INIT_STATE, 2_000_000)
    st, code = request_state(m, s, pysoem.PREOP_STATE)
    s.dc_sync(1, 10_000)
    st, code = request_state(m, s, pysoem.SAFEOP_STATE)
    check(st == 0x12 and code == 0x0035, f"SYNC0 every 10 us refused: AL status {st:#06x}, code {code:#06x}")
    m.close()


MODULE_IDENT = 0x0022_0001


def dma22(iface):
    """HCS DMA-22(A) node, 3 modules in mode 3 (modular device, ETG.5001):
    a wrong configured module list (0xF030) is refused at SAFE-OP with
    AL status 0x0070; with the right one the node reaches OP and the
    manual's 5.4.2 set values (1.000 V, 2.000 V, -3.000 V) come back as
    each module's desired value d1.10 with HW enable set."""
    m, n = open_master(iface)
    check(n == 1, f"SOEM config_init found {n} slave(s) (1 expected)")
    s = m.slaves[0]
    check(s.name == "DMA-22(A)-ECAT", f"SII name {s.name!r}")
    detected = s.sdo_read(0xF050, 0)[0]
    idents = [struct.unpack("<I", s.sdo_read(0xF050, k))[0] for k in range(1, detected + 1)]
    check(detected == 3 and idents == [MODULE_IDENT] * 3,
          f"0xF050 detected module list: {detected} x {[hex(i) for i in idents]}")
    set_sm_watchdog(m, LONG_WATCHDOG_MS)
    for k in (1, 2):
        s.sdo_write(0xF030, k, struct.pack("<I", MODULE_IDENT))
    s.sdo_write(0xF030, 0, bytes([2]))
    size = m.config_map()
    log(f"      config_map: I/O map {size} bytes, outputs {len(s.output)}, inputs {len(s.input)}")
    check((len(s.output), len(s.input)) == (15, 18),
          "3 module PDOs each way: 5 bytes out and 6 bytes in per module")
    st, code = request_state(m, s, pysoem.SAFEOP_STATE)
    check(st == 0x12 and code == 0x0070,
          f"2 modules configured, 3 detected: AL status {st:#06x}, code {code:#06x} (0x0012, 0x0070)")
    st, code = request_state(m, s, pysoem.PREOP_STATE | 0x10)
    check(st == 0x02, f"error acknowledged: AL status {st:#06x}")
    # The refusal also came as a CoE Emergency (0xA000 "transition
    # refused", the AL status code in its data); SOEM hands it over with
    # the next mailbox exchange.
    try:
        s.sdo_read(0x1000, 0)
        emcy = None
    except pysoem.Emergency as e:
        emcy = e
    check(emcy is not None and emcy.error_code == 0xA000 and emcy.b1 == 0x70,
          f"Emergency for the refusal: {emcy}")
    s.sdo_write(0xF030, 3, struct.pack("<I", MODULE_IDENT))
    s.sdo_write(0xF030, 0, bytes([3]))
    check(to_op(m), "OP with the configured module list equal to the detected one")
    values = [1000, 2000, -3000]
    s.output = b"".join(struct.pack("<Bhh", 0, v, 0) for v in values)
    wkcs = cycles(m, 50)
    check(all(w == m.expected_wkc for w in wkcs[5:]), f"50 cycles with WKC {m.expected_wkc}")
    got = [struct.unpack_from("<Hhh", s.input, 6 * k) for k in range(3)]
    log(f"      modules answer (status, value 1 = d1.11, value 2 = d1.10): {got}")
    check(got == [(0x0400, 0, v) for v in values],
          "each module: HW enable, feedback 0, desired value = its set value (manual 5.4.2)")
    m.close()


def eni_coe_init_cmds(eni, transition):
    """Per ENI slave (in order): the CoE init commands of `transition`
    as (index, subindex, data, complete access, comment)."""
    out = []
    for sl in ET.parse(eni).getroot().iter("Slave"):
        cmds = []
        for c in sl.findall("Mailbox/CoE/InitCmds/InitCmd"):
            if transition not in [t.text for t in c.findall("Transition")]:
                continue
            num = lambda t: int(t.replace("#x", "0x"), 0)
            cmds.append((num(c.find("Index").text), num(c.find("SubIndex").text),
                         bytes.fromhex(c.find("Data").text), c.get("CompleteAccess") == "1",
                         c.findtext("Comment", "")))
        out.append(cmds)
    return out


def twins(iface, spec, eni):
    want = [w.split("|") for w in spec.split(";")]
    m, n = open_master(iface)
    check(n == len(want), f"SOEM config_init found {n} slave(s) ({len(want)} expected)")
    init = eni_coe_init_cmds(eni, "PS")
    done = 0
    for s, cmds in zip(m.slaves, init):
        for index, sub, data, ca, comment in cmds:
            s.sdo_write(index, sub, data, ca)
            done += 1
    check(done > 0, f"the ENI's {done} CoE init commands (PS) downloaded by SOEM without an abort")
    for i, (s, w) in enumerate(zip(m.slaves, want)):
        name, vendor, product, rev = w[0], int(w[1], 0), int(w[2], 0), int(w[3], 0)
        log(f"      slave {i + 1}: {s.name!r} man {s.man:#010x} id {s.id:#010x} rev {s.rev:#010x}")
        check(s.name == name, f"slave {i + 1} name {s.name!r} ({name!r})")
        check((s.man, s.id, s.rev) == (vendor, product, rev),
              f"slave {i + 1} identity {s.man:#x}/{s.id:#010x}/{s.rev:#010x}")
    set_sm_watchdog(m, LONG_WATCHDOG_MS)
    size = m.config_map()
    log(f"      config_map: I/O map {size} bytes, expected WKC {m.expected_wkc}")
    for i, (s, w) in enumerate(zip(m.slaves, want)):
        out_b, in_b = int(w[4]), int(w[5])
        check((len(s.output), len(s.input)) == (out_b, in_b),
              f"slave {i + 1} {s.name}: {len(s.output)} output / {len(s.input)} input bytes ({out_b}/{in_b})")
    check(to_op(m), "every slave in OP")
    # The working counter ETG.1000.4 gives one LRW over this line: +2 for
    # each slave that writes outputs, +1 for each that reads inputs, as
    # the real devices count. SOEM 1.4 (inside pysoem 1.1.13) expects less:
    # its ecx_config_map counts a slave's outputs only when the logical
    # address advanced, and a 4-bit slave (EL2004) packed into a byte does
    # not advance it; newer SOEM forces byte alignment for such slaves.
    etg_wkc = sum(2 * (len(s.output) > 0) + (len(s.input) > 0) for s in m.slaves)
    log(f"      working counter per ETG.1000.4: {etg_wkc}; SOEM's expected_wkc: {m.expected_wkc}")
    seen = set()
    bad = []
    for _ in range(100):
        for s in m.slaves:
            if len(s.output) == 1:
                s.output = bytes([0xA5])
        m.send_processdata()
        w = m.receive_processdata(RECEIVE_TIMEOUT_US)
        if w != etg_wkc:
            bad.append(w)
        for s in m.slaves:
            if s.name == "EL1008":
                seen.add(bytes(s.input))
        time.sleep(0.001)
    check(not bad, f"100 cycles with WKC {etg_wkc} ({len(bad)} others: {bad[:5]})")
    check(len(seen) > 10, f"the counter twin's inputs move ({len(seen)} distinct values)")
    states = [al_status(s) for s in m.slaves]
    check(all(st == 0x08 for st in states), f"AL status of every slave {[hex(x) for x in states]}")
    for s, cmds in zip(m.slaves, init):
        for index, sub, data, ca, comment in cmds:
            if index in (0x1C12, 0x1C13) or ca:
                continue
            got = s.sdo_read(index, sub)
            check(got == data, f"{s.name} {index:#06x}:{sub} ({comment}) reads back {got.hex()} ({data.hex()})")
    m.close()


def esi_twin(iface, esi):
    root = ET.parse(esi).getroot()
    dev = root.find("Descriptions/Devices/Device")
    typ = dev.find("Type")
    hexv = lambda t: int(t.replace("#x", "0x"), 16)
    vendor = hexv(root.find("Vendor/Id").text)
    product, revision = hexv(typ.get("ProductCode")), hexv(typ.get("RevisionNo"))
    m, n = open_master(iface)
    check(n == 1, f"SOEM config_init found {n} slave(s) (1 expected)")
    s = m.slaves[0]
    log(f"      {s.name!r} man {s.man:#010x} id {s.id:#010x} rev {s.rev:#010x}")
    check(s.name == typ.text, f"name {s.name!r} is the ESI type {typ.text!r}")
    check((s.man, s.id, s.rev) == (vendor, product, revision), "identity as the ESI says")
    ids = [struct.unpack("<I", s.sdo_read(0x1018, k))[0] for k in (1, 2, 3)]
    check(ids == [vendor, product, revision], f"0x1018:01..03 over SDO {[hex(i) for i in ids]}")
    coe = dev.find("Mailbox/CoE")
    offers = lambda a: coe is not None and coe.get(a) in ("1", "true")
    # Without complete access in the ESI, the twin aborts it (0x06010000).
    if not offers("CompleteAccess"):
        try:
            s.sdo_read(0x1018, 1, ca=True)
            check(False, "complete access refused, but the upload was served")
        except pysoem.SdoError as e:
            check(e.abort_code == 0x06010000,
                  f"complete access aborted with {e.abort_code:#010x} (0x06010000 expected)")
    bits = {"R": 0, "T": 0}
    for kind, tag in (("R", "RxPdo"), ("T", "TxPdo")):
        for p in dev.iter(tag):
            if p.get("Sm") is not None:
                bits[kind] += sum(int(e.find("BitLen").text) for e in p.iter("Entry"))
    set_sm_watchdog(m, LONG_WATCHDOG_MS)
    size = m.config_map()
    log(f"      config_map: I/O map {size} bytes, outputs {len(s.output)}, inputs {len(s.input)}")
    check((len(s.output), len(s.input)) == ((bits["R"] + 7) // 8, (bits["T"] + 7) // 8),
          f"image sizes from the ESI's default PDOs ({bits['R']} / {bits['T']} bits)")
    check(to_op(m), "OP")
    s.output = bytes([0xA5] * len(s.output))
    wkcs = cycles(m, 30)
    check(all(w == m.expected_wkc for w in wkcs[5:]), f"30 cycles with WKC {m.expected_wkc}")
    log(f"      outputs {bytes(s.output).hex()} inputs {bytes(s.input).hex()}")
    check(bytes(s.input)[:1] == b"\xa5", "the loopback twin's inputs carry its outputs")
    if offers("SdoInfo"):
        od = s.od
        live = [o.index for o in od]
        want = esi_object_indices(esi)
        check(live == want, f"SDO Information lists {len(live)} objects, the ESI {len(want)}: equal")
        names = {hexv(o.find("Index").text): o.find("Name").text for o in root.iter("Object")}
        text = lambda v: v.decode() if isinstance(v, bytes) else v
        wrong = [hex(o.index) for o in od if names.get(o.index) != text(o.name)]
        check(not wrong, f"every object's name as in the ESI (wrong: {wrong})")
    else:
        # The ESI offers no SDO Information: the twin refuses it (mailbox
        # error 0x0004) instead of serving it anyway. Last: SOEM keeps the
        # refusal in its error list, and config_map would report it.
        try:
            od = s.od
            check(False, f"SDO Information refused, but SOEM read {len(od)} objects")
        except (pysoem.SdoInfoError, pysoem.MailboxError) as e:
            check(True, f"SDO Information refused as the ESI says ({type(e).__name__}: {e})")
    m.close()


def safety(iface):
    """The PAM's safety rules (docs/SAFETY.md) as SOEM can try to break
    them: finding 1 to 3 of issue 29."""
    u8 = lambda v: struct.pack("<B", v)
    u32 = lambda v: struct.pack("<I", v)
    # Finding 1: no RxPDO, ENABLE and a command value over SDO in OP.
    m, n = open_master(iface)
    check(n == 1, f"SOEM finds {n} slave")
    s = m.slaves[0]
    # The refused SAFE-OP below sends an Emergency; SOEM hands it over here
    # instead of raising it from the next SDO transfer.
    s.add_emergency_callback(lambda e: log(f"      emergency: {e}"))
    set_sm_watchdog(m, LONG_WATCHDOG_MS)
    s.sdo_write(0x1C12, 0, u8(0))
    m.config_map()
    check(len(s.output) == 0, f"no RxPDO assigned: output image {len(s.output)} bytes")
    # SOEM 1.4's config_map keeps the SII's SM2 length (5) with the empty
    # assignment and requests SAFE-OP, which the slave refuses with 0x001D
    # (as SOES does: SM2 length must be the image's, 0). The master then
    # disables SM2, as the finding's reproduction did, and acknowledges.
    st, code = al_status(s), al_status_code(s)
    log(f"      after config_map: AL status {st:#06x} code {code:#06x}")
    s._fpwr(0x0816, b"\x00", 20000)
    st, code = request_state(m, s, pysoem.PREOP_STATE | 0x10)
    log(f"      SM2 disabled, error acknowledged: AL status {st:#06x}")
    ok = check(to_op(m), "OP without outputs")
    if not ok:
        log(f"      AL status {al_status(s):#06x} code {al_status_code(s):#06x}")
    s.sdo_write(0x7000, 1, u8(1))
    s.sdo_write(0x7000, 3, struct.pack("<i", 5000))
    cycles(m, 500)
    ia = struct.unpack("<H", s.sdo_read(0x6000, 6))[0]
    st = al_status(s)
    log(f"      after 1 s: IA {ia} mA, AL status {st:#06x}")
    check(ia == 0, f"ENABLE and COMMAND written by SDO without cyclic outputs drive no current: IA {ia} mA")
    check(st == 0x08, f"and the slave is still in OP: {st:#06x}")
    m.close()
    # Finding 2: FUNCTION = IND in PRE-OP, OP, then DEFAULT / LOADBACK.
    m, n = open_master(iface)
    s = m.slaves[0]
    set_sm_watchdog(m, LONG_WATCHDOG_MS)
    s.sdo_write(0xF800, 2, u8(1))
    s.sdo_write(0xF801, 2, u32(1))  # SAVE with FUNCTION = DIR
    s.sdo_write(0xF800, 2, u8(2))
    a = struct.unpack("<H", s.sdo_read(0x1C12, 1))[0]
    check(a == 0x1601, f"FUNCTION = IND selects 0x1601: 0x1C12:01 = {a:#06x}")
    m.config_map()
    check(to_op(m), "OP with the independent set")
    for sub, what in ((3, "DEFAULT"), (4, "LOADBACK")):
        code = abort_of(lambda: s.sdo_write(0xF801, sub, u32(1)))
        check(code == 0x08000022, f"{what} in OP that would change FUNCTION: abort {code and hex(code)}")
        f = s.sdo_read(0xF800, 2)[0]
        check(f == 2, f"FUNCTION still IND after {what}: {f}")
    cycles(m, 10)
    st = al_status(s)
    check(st == 0x08, f"OP, no error: {st:#06x}")
    # Finding 3: SAVE with FUNCTION = IND (1 s after the first SAVE).
    time.sleep(1.1)
    s.sdo_write(0xF801, 2, u32(1))
    log("      SAVE with FUNCTION = IND; the runner restarts (power cycle)")
    m.close()


def safety_after_power_cycle(iface):
    """After the power cycle: FUNCTION = IND came back with its PDO set."""
    m, n = open_master(iface)
    check(n == 1, f"SOEM finds {n} slave after the power cycle")
    s = m.slaves[0]
    set_sm_watchdog(m, LONG_WATCHDOG_MS)
    f = s.sdo_read(0xF800, 2)[0]
    rx = struct.unpack("<H", s.sdo_read(0x1C12, 1))[0]
    tx = struct.unpack("<H", s.sdo_read(0x1C13, 1))[0]
    check((f, rx, tx) == (2, 0x1601, 0x1A01),
          f"FUNCTION {f} with 0x1C12:01 {rx:#06x}, 0x1C13:01 {tx:#06x} (IND, 0x1601, 0x1A01)")
    m.config_map()
    check(to_op(m), "OP without rewriting the assignment")
    m.close()


IO8_VENDOR = 0x0000_0ABE
IO8_PRODUCT = 0x0000_0008


def open_board(iface):
    """open_master for the board: SOEM's discovery (BRD with its
    compiled-in 20 ms timeout) is tried again, up to 5 times, when a
    loaded machine kept the bridge from answering in time; the log says
    so."""
    for attempt in range(5):
        m, n = open_master(iface)
        if n >= 1:
            return m, n
        log(f"      config_init returned {n} (attempt {attempt + 1}), again")
        m.close()
        time.sleep(0.2)
    return m, n


def board(iface, esi, sii_path, good_efw, bad_efw, boot_out, boot_in):
    m, n = open_board(iface)
    check(n == 1, f"SOEM config_init found {n} slave(s) (1 expected)")
    s = m.slaves[0]
    log(f"      vendor {s.man:#010x} product {s.id:#010x} revision {s.rev} name {s.name!r}")
    check((s.man, s.id, s.rev) == (IO8_VENDOR, IO8_PRODUCT, 1),
          "identity (vendor 0x0ABE, product 0x00000008, revision 1)")
    check(s.name == "IO8", f"named 'IO8': {s.name!r}")
    set_sm_watchdog(m, LONG_WATCHDOG_MS)
    name = s.sdo_read(0x1008, 0).decode()
    check(name == "IO8", f"0x1008 DEVICE NAME = {name!r}")
    version = s.sdo_read(0x100A, 0).decode()
    log(f"      0x100A software version {version!r}")

    # --- SDO upload/download and the abort codes SOEM reports
    s.sdo_write(0x8000, 1, struct.pack("<H", 20))
    check(struct.unpack("<H", s.sdo_read(0x8000, 1))[0] == 20, "SDO download/upload 0x8000:01 input filter = 20 ms")
    aborts = {
        "out of range 0x8000:01 = 5000": (lambda: s.sdo_write(0x8000, 1, struct.pack("<H", 5000)), 0x06090031),
        "read-only 0x1018:01": (lambda: s.sdo_write(0x1018, 1, struct.pack("<I", 1)), 0x06010002),
        "unknown object 0x1234": (lambda: s.sdo_read(0x1234, 0), 0x06020000),
        "unknown subindex 0x1018:07": (lambda: s.sdo_read(0x1018, 7), 0x06090011),
    }
    for what, (fn, want) in aborts.items():
        got = abort_of(fn)
        check(got == want, f"abort for {what}: SOEM got {got if got is None else hex(got)}, want {want:#010x}")
    check(struct.unpack("<H", s.sdo_read(0x8000, 1))[0] == 20, "a refused write leaves 0x8000:01 at 20")
    s.sdo_write(0x8000, 1, struct.pack("<H", 10))

    # --- SDO Information: the object list and entries of the ESI
    live = [o.index for o in s.od]
    want = esi_object_indices(esi)
    check(live == want, f"SDO Information lists {len(live)} objects, the ESI {len(want)}: equal")
    o6000 = {o.index: o for o in s.od}.get(0x6000)
    check(o6000 is not None and len(o6000.entries) == 9 and o6000.entries[1].name == b"Input 1",
          "SDO Information: 0x6000 has subindex 0..8, 'Input 1'")

    # --- the SII through SOEM equals `esi sii`
    want_sii = open(sii_path, "rb").read()
    got = bytearray()
    for word in range(0, len(want_sii) // 2, 2):
        got += s.eeprom_read(word)
    check(bytes(got) == want_sii, f"SII read by SOEM ({len(got)} bytes) equals `esi sii`")

    # --- state machine
    st, code = request_state(m, s, pysoem.INIT_STATE)
    st, code = request_state(m, s, pysoem.OP_STATE)
    check(st == 0x11 and code == 0x0011, f"INIT->OP refused: AL status {st:#06x}, code {code:#06x}")
    st, code = request_state(m, s, pysoem.INIT_STATE | pysoem.STATE_ACK)
    check(st == 0x01, f"acknowledged back to INIT: {st:#06x}")
    st, code = request_state(m, s, pysoem.PREOP_STATE)
    check(st == 0x02, f"INIT->PRE-OP: {st:#06x}")

    # --- process data: OP, 1000 cycles, the outputs come back as inputs
    m.read_state()
    set_sm_watchdog(m, LONG_WATCHDOG_MS)
    size = m.config_map()
    log(f"      config_map: I/O map {size} bytes, expected WKC {m.expected_wkc}")
    check((len(s.output), len(s.input), m.expected_wkc) == (1, 1, 3), "1 output byte, 1 input byte, WKC 3")
    check(to_op(m), "OP")
    wkcs = []
    seen = []
    for k in range(1000):
        s.output = bytes([k // 100 * 0x11 & 0xFF])
        m.send_processdata()
        wkcs.append(m.receive_processdata(RECEIVE_TIMEOUT_US))
        seen.append(bytes(s.input)[0])
        time.sleep(0.0005)
    bad = [w for w in wkcs if w != m.expected_wkc]
    log(f"      1000 cycles: working counters min {min(wkcs)} max {max(wkcs)}, {len(bad)} unexpected; "
        f"inputs seen {sorted(set(seen))}")
    check(not bad, "1000 cycles, every working counter as expected")
    fixed_mapping_by_complete_access(s, "OP on the board firmware")
    sent = set(range(0, 0x9A, 0x11))
    check(set(seen) <= sent, f"every input value seen is an output sent ({sorted(set(seen) - sent)} others)")
    # The last output held until it comes back (the IO8 filters inputs
    # for 10 ms; a firmware in an emulator may take longer under load).
    back = None
    for _ in range(1000):
        m.send_processdata()
        m.receive_processdata(RECEIVE_TIMEOUT_US)
        back = bytes(s.input)[0]
        if back == 0x99:
            break
        time.sleep(0.002)
    check(back == 0x99, f"the looped-back output 0x99 came back as the input: {back:#04x}")

    # --- SM watchdog (100 ms): outputs stopped -> SAFE-OP + 0x001B, back to OP
    set_sm_watchdog(m, 100)
    cycles(m, 5)
    time.sleep(0.3)
    st, code = al_status(s), al_status_code(s)
    check(st == 0x14 and code == 0x001B, f"outputs stopped 300 ms: AL status {st:#06x}, code {code:#06x}")
    s.state = pysoem.SAFEOP_STATE | pysoem.STATE_ACK
    s.write_state()
    cycles(m, 20)
    st, code = request_state(m, s, pysoem.OP_STATE)
    for _ in range(200):
        cycles(m, 1)
        st = al_status(s)
        if st == 0x08:
            break
    check(st == 0x08, f"acknowledged, outputs flowing, OP again: {st:#06x}")
    set_sm_watchdog(m, LONG_WATCHDOG_MS)
    m.close()

    # --- FoE in BOOT, as SOEM's firmware-update example does it
    m, n = open_board(iface)
    s = m.slaves[0]
    m.state = pysoem.INIT_STATE
    m.write_state()
    m.state_check(pysoem.INIT_STATE, 2_000_000)
    (bo, bol), (bi, bil) = [tuple(int(x, 16) for x in a.split(":")) for a in (boot_out, boot_in)]
    s.amend_mbx("out", bo, bol)
    s.amend_mbx("in", bi, bil)
    st, code = request_state(m, s, pysoem.BOOT_STATE)
    check(st == 0x03, f"INIT->BOOT with the bootstrap mailbox: {st:#06x} code {code:#06x}")
    r = foe_write(s, "io8.efw", 0, open(bad_efw, "rb").read())
    log(f"      foe_write of a corrupt image returned {r}")
    check(r == -5, "corrupt image refused with an FoE error (SOEM -5)")
    good = open(good_efw, "rb").read()
    t = time.monotonic()
    # A firmware in an emulator on a loaded machine answers late more
    # often than a runner: up to three downloads (each with foe_write's
    # own retry), never after a refusal (-5).
    for attempt in range(3):
        r = foe_write(s, "io8.efw", 0, good)
        if r > 0 or r == -5:
            break
        log(f"      download attempt {attempt + 1} returned {r}; starting it again")
        time.sleep(0.5)
    log(f"      foe_write of {len(good)} bytes returned {r} in {time.monotonic() - t:.3f} s")
    check(r > 0, "good image written")
    st, code = request_state(m, s, pysoem.INIT_STATE)
    check(st == 0x01, f"BOOT->INIT (image committed for the next boot): {st:#06x} code {code:#06x}")
    # The commit is a boot-record write over the emulated flash that may
    # finish after INIT shows; the test resets the board (kills QEMU)
    # next, and a reset before the write ends boots the old image, as a
    # power cut would. A second's grace.
    time.sleep(1.0)
    m.close()


def board_after_restart(iface, version):
    m, n = open_board(iface)
    check(n == 1, f"after the restart SOEM finds {n} slave(s)")
    s = m.slaves[0]
    set_sm_watchdog(m, LONG_WATCHDOG_MS)
    v = s.sdo_read(0x100A, 0).decode()
    check(v == version, f"0x100A after the restart: {v!r} (the downloaded {version!r})")
    m.config_map()
    check(to_op(m), "OP after the update")
    wkcs = cycles(m, 100, 0.0005)
    check(all(w == m.expected_wkc for w in wkcs), "100 cycles after the update")
    m.close()


# servo402's default PDOs: 0x1600 controlword, target position, target
# velocity, target torque, modes of operation; 0x1A00 statusword,
# position, velocity, torque, modes of operation display, following
# error, error code. SOEM writes its own mapping instead (below):
# controlword, target position, modes of operation out; statusword,
# position, following error, error code in.
SERVO_OUT = struct.Struct("<HiB")
SERVO_IN = struct.Struct("<HiiH")
# Statusword state coding (CiA 402, mask 0x6F / 0x4F).
SWITCH_ON_DISABLED, READY, SWITCHED_ON, ENABLED = 0x40, 0x21, 0x23, 0x27


def mapping(index, bits, sub=0):
    return struct.pack("<I", index << 16 | sub << 8 | bits)


def csp_exchange(m, s, out, inp):
    """One cycle of a drive in CSP, `n` times: controlword and target
    position (mode 8) out as `out` packs them, the inputs back as `inp`
    unpacks them; 1 ms between cycles."""

    def exchange(controlword, target, n=1):
        for _ in range(n):
            s.output = out.pack(controlword, target, 8)
            m.send_processdata()
            m.receive_processdata(RECEIVE_TIMEOUT_US)
            time.sleep(0.001)
        return inp.unpack(bytes(s.input))

    return exchange


def servo402_mapping(s):
    """The master's PDO configuration in PRE-OP, in ETG.1020's order: the
    assignment emptied, each mapping's subindex 0 to 0, its entries, its
    count, then the assignment. Every refusal the slave owes on the way is
    checked with its abort code."""

    def aborts(index, sub, data, code, what):
        try:
            s.sdo_write(index, sub, data)
        except pysoem.SdoError as e:
            check(e.abort_code == code, f"{what}: abort {e.abort_code:#010x} ({code:#010x} expected)")
            return
        check(False, f"{what}: accepted ({code:#010x} expected)")

    aborts(0x1600, 1, mapping(0x6040, 16), 0x06010003, "an entry while subindex 0 is 5")
    for index in (0x1C12, 0x1C13):
        s.sdo_write(index, 0, bytes([0]))
    s.sdo_write(0x1600, 0, bytes([0]))
    aborts(0x1600, 1, mapping(0x6041, 16), 0x06040041, "the statusword in an RxPDO")
    aborts(0x1600, 1, mapping(0x6040, 32), 0x06040041, "the controlword with 32 bits")
    for sub, m in enumerate((mapping(0x6040, 16), mapping(0x607A, 32), mapping(0x6060, 8)), 1):
        s.sdo_write(0x1600, sub, m)
    s.sdo_write(0x1600, 4, bytes(4))
    aborts(0x1600, 0, bytes([4]), 0x06040043, "a count over a cleared place")
    s.sdo_write(0x1600, 0, bytes([3]))
    s.sdo_write(0x1A00, 0, bytes([0]))
    tx = (mapping(0x6041, 16), mapping(0x6064, 32), mapping(0x60F4, 32), mapping(0x603F, 16))
    for sub, m in enumerate(tx, 1):
        s.sdo_write(0x1A00, sub, m)
    s.sdo_write(0x1A00, 0, bytes([4]))
    for index, pdo in ((0x1C12, 0x1600), (0x1C13, 0x1A00)):
        s.sdo_write(index, 1, struct.pack("<H", pdo))
        s.sdo_write(index, 0, bytes([1]))
    s.sdo_write(0x6060, 0, struct.pack("<b", 8))


def servo402(iface):
    m, n = open_master(iface)
    check(n == 1, f"SOEM config_init found {n} slave(s) (1 expected)")
    s = m.slaves[0]
    check(s.name == "SERVO402", f"SII name {s.name!r}")
    modes = struct.unpack("<I", s.sdo_read(0x6502, 0))[0]
    check(modes & 0x380 == 0x380, f"0x6502 supported drive modes {modes:#x}: CSP, CSV, CST")
    # The mapping is written in SOEM's configuration hook, which
    # config_map calls in PRE-OP before it reads the PDOs over CoE.
    configured = []

    def hook(_pos):
        servo402_mapping(s)
        configured.append(True)

    s.config_func = hook
    check(bool(m.config_dc()), "config_dc: the drive has DC")
    set_sm_watchdog(m, LONG_WATCHDOG_MS)
    cycle_ns = 1_000_000
    s.dc_sync(True, cycle_ns)
    m.config_map()
    check(configured == [True], "SOEM ran the configuration hook")
    check(struct.unpack("<B", s.sdo_read(0x1600, 0))[0] == 3, "0x1600 holds 3 entries")
    check(struct.unpack("<b", s.sdo_read(0x6061, 0))[0] == 8, "0x6061 shows CSP")
    check((len(s.output), len(s.input)) == (SERVO_OUT.size, SERVO_IN.size),
          f"process image {len(s.output)} bytes out, {len(s.input)} in "
          f"({SERVO_OUT.size}, {SERVO_IN.size}: the written mapping)")
    check(to_op(m), "OP, DC-synchronous")
    sync = struct.unpack("<H", s.sdo_read(0x1C32, 1))[0]
    check(sync == 2, f"0x1C32:01 sync mode {sync} (2: DC SYNC0)")
    try:
        s.sdo_write(0x1600, 0, bytes([0]))
        check(False, "the mapping written in OP")
    except pysoem.SdoError as e:
        check(e.abort_code == 0x08000022, f"the mapping in OP: abort {e.abort_code:#010x}")

    exchange = csp_exchange(m, s, SERVO_OUT, SERVO_IN)

    def command(controlword, target, want, mask=0x6F):
        for _ in range(500):
            sw = exchange(controlword, target)[0]
            if sw & mask == want:
                break
        return sw

    sw, pos, *_ = exchange(0, 0, 10)
    check(sw & 0x4F == SWITCH_ON_DISABLED, f"statusword {sw:#06x}: Switch on disabled")
    target = pos
    for cw, want in ((0x0006, READY), (0x0007, SWITCHED_ON), (0x000F, ENABLED)):
        sw = command(cw, target, want)
        check(sw & 0x6F == want, f"controlword {cw:#06x}: statusword {sw:#06x}")
    check(sw & 0x1000 != 0, "CSP: the target position is used (bit 12)")
    start, worst, err = pos, 0, 0
    # 20 inc per cycle; the drive follows on its own clock.
    for _ in range(1000):
        target += 20
        sw, pos, fe, err = exchange(0x000F, target)
        worst = max(worst, abs(fe))
        if sw & 0x6F != ENABLED or err:
            break
    check(sw & 0x6F == ENABLED and err == 0, f"the ramp ran in Operation enabled: {sw:#06x}, error {err:#06x}")
    log(f"      ramp of {target - start} inc: following error up to {worst} inc")
    check(worst <= 5000, f"following error within the 5000 inc window ({worst})")
    sw, pos, fe, err = exchange(0x000F, target, 100)
    check(abs(target - pos) <= 10, f"position {pos} on the target {target}")
    check(pos - start >= 19_000, f"the axis moved {pos - start} inc")
    sw = command(0x0002, target, SWITCH_ON_DISABLED, 0x4F)
    check(sw & 0x4F == SWITCH_ON_DISABLED, f"quick stop: statusword {sw:#06x}, Switch on disabled")
    sw, *_, err = exchange(0, target, 5)
    check(err == 0, f"no fault after the quick stop ({err:#06x})")
    m.state = pysoem.INIT_STATE
    m.write_state()
    m.state_check(pysoem.INIT_STATE, 2_000_000)
    m.close()


def corpus(iface, spec, drive):
    """Twins of vendors' devices from their own ESI files (the corpus of
    ../shared): identities and names as their ESIs give them, OP, and the
    CiA 402 drive at position DRIVE (1-based) configured as a user does:
    a mapping of SOEM's own written in its configuration hook (the drive's
    ESI marks its PDOs not Fixed and its mapping entries rw in PRE-OP),
    DC with SYNC0 every 1 ms, the drive's state machine to Operation
    enabled in CSP and a target ramp the position follows."""
    want = [w.split("|") for w in spec.split(";")]
    drive = int(drive) - 1
    m, n = open_master(iface)
    check(n == len(want), f"SOEM config_init found {n} slave(s) ({len(want)} expected)")
    for i, (s, w) in enumerate(zip(m.slaves, want)):
        name, vendor, product, rev = w[0], int(w[1], 0), int(w[2], 0), int(w[3], 0)
        log(f"      slave {i + 1}: {s.name!r} man {s.man:#010x} id {s.id:#010x} rev {s.rev:#010x}")
        check(s.name == name, f"slave {i + 1} name {s.name!r} ({name!r})")
        check((s.man, s.id, s.rev) == (vendor, product, rev),
              f"slave {i + 1} identity {s.man:#x}/{s.id:#010x}/{s.rev:#010x}")
    d = m.slaves[drive]
    device_type = struct.unpack("<I", d.sdo_read(0x1000, 0))[0]
    log(f"      drive 0x1000 = {device_type:#010x}")
    configured = []

    def hook(_pos):
        for index in (0x1C12, 0x1C13):
            d.sdo_write(index, 0, bytes([0]))
        d.sdo_write(0x1600, 0, bytes([0]))
        for sub, v in enumerate((mapping(0x6040, 16), mapping(0x607A, 32), mapping(0x6060, 8)), 1):
            d.sdo_write(0x1600, sub, v)
        d.sdo_write(0x1600, 0, bytes([3]))
        d.sdo_write(0x1A00, 0, bytes([0]))
        for sub, v in enumerate((mapping(0x6041, 16), mapping(0x6064, 32)), 1):
            d.sdo_write(0x1A00, sub, v)
        d.sdo_write(0x1A00, 0, bytes([2]))
        for index, pdo in ((0x1C12, 0x1600), (0x1C13, 0x1A00)):
            d.sdo_write(index, 1, struct.pack("<H", pdo))
            d.sdo_write(index, 0, bytes([1]))
        d.sdo_write(0x6060, 0, struct.pack("<b", 8))
        configured.append(True)

    d.config_func = hook
    check(bool(m.config_dc()), "config_dc")
    set_sm_watchdog(m, LONG_WATCHDOG_MS)
    d.dc_sync(True, 1_000_000)
    size = m.config_map()
    log(f"      config_map: I/O map {size} bytes, expected WKC {m.expected_wkc}")
    check(configured == [True], "SOEM ran the drive's configuration hook")
    check((len(d.output), len(d.input)) == (7, 6),
          f"the drive's image {len(d.output)}/{len(d.input)} bytes: the written mapping (7/6)")
    check(to_op(m), "every slave in OP")
    states = [al_status(s) for s in m.slaves]
    check(all(st == 0x08 for st in states), f"AL status of every slave {[hex(x) for x in states]}")
    exchange = csp_exchange(m, d, struct.Struct("<HiB"), struct.Struct("<Hi"))

    sw, pos = exchange(0, 0, 10)
    check(sw & 0x4F == SWITCH_ON_DISABLED, f"drive statusword {sw:#06x}: Switch on disabled")
    target = pos
    for cw, st in ((0x0006, READY), (0x0007, SWITCHED_ON), (0x000F, ENABLED)):
        for _ in range(500):
            sw, pos = exchange(cw, target)
            if sw & 0x6F == st:
                break
        check(sw & 0x6F == st, f"controlword {cw:#06x}: statusword {sw:#06x}")
    start = pos
    for _ in range(500):
        target += 20
        sw, pos = exchange(0x000F, target)
        if sw & 0x6F != ENABLED:
            break
    check(sw & 0x6F == ENABLED, f"the ramp ran in Operation enabled ({sw:#06x})")
    sw, pos = exchange(0x000F, target, 100)
    check(abs(target - pos) <= 10 and pos - start >= 9_000,
          f"the position {pos} followed the ramp to {target} (from {start})")
    m.state = pysoem.INIT_STATE
    m.write_state()
    m.state_check(pysoem.INIT_STATE, 2_000_000)
    m.close()


def main():
    if len(sys.argv) < 3:
        print(__doc__)
        return 2
    log(f"pysoem {getattr(pysoem, '__version__', '?')}")
    if sys.argv[1] == "phase1":
        phase1(*sys.argv[2:9])
    elif sys.argv[1] == "phase2":
        phase2(*sys.argv[2:4])
    elif sys.argv[1] == "chain":
        chain(*sys.argv[2:4])
    elif sys.argv[1] == "dc":
        dc(*sys.argv[2:4])
    elif sys.argv[1] == "dma22":
        dma22(*sys.argv[2:3])
    elif sys.argv[1] == "twins":
        twins(*sys.argv[2:5])
    elif sys.argv[1] == "esi_twin":
        esi_twin(*sys.argv[2:4])
    elif sys.argv[1] == "safety":
        safety(*sys.argv[2:3])
    elif sys.argv[1] == "safety_after_power_cycle":
        safety_after_power_cycle(*sys.argv[2:3])
    elif sys.argv[1] == "board":
        board(*sys.argv[2:9])
    elif sys.argv[1] == "board_after_restart":
        board_after_restart(*sys.argv[2:4])
    elif sys.argv[1] == "servo402":
        servo402(*sys.argv[2:3])
    elif sys.argv[1] == "corpus":
        corpus(*sys.argv[2:5])
    else:
        print(__doc__)
        return 2
    if FAILURES:
        log(f"{len(FAILURES)} check(s) failed")
        return 1
    log("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
