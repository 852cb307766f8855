#!/usr/bin/env bash
# Firmware footprint of the ecat-slave core with the IO8 example device and
# with the PAM-199-P-ETC, measured on a real link of a no_std firmware.
#
#   bash scripts/footprint.sh
#
# For each device (and an empty baseline) it builds the no_std staticlib of
# examples/firmware (opt-level "z", LTO, panic=abort, codegen-units=1; see
# its Cargo.toml), links it with the C harness (gcc -Os, --gc-sections,
# -no-pie), runs the harness (a simulated master drives the firmware through
# INIT, PRE-OP with SDO / SDO Information / complete access, SAFE-OP, OP,
# watchdog, PDI failure, BOOT with an FoE download) and prints:
#
#   * text, rodata, .data.rel.ro (constant tables holding pointers), data,
#     bss of the firmware: the device's binary minus the baseline (the same
#     harness linked against the empty firmware);
#   * the biggest firmware symbols (nm --size-sort);
#   * the stack of one fw_poll: measured by stack painting over the
#     harness's traffic, and a static estimate from the call graph of the
#     disassembly;
#   * core::mem::size_of of the firmware object's parts and what the object
#     dictionary tables are made of (a small host program).
#
# Then the same firmware for a Cortex-M4 (thumbv7em-none-eabihf, linked
# with arm-none-eabi-gcc against examples/firmware/cortex_m4.c, the board
# functions as stubs that cancel out with the baseline): text, rodata,
# data, bss and a static estimate of the stack of one fw_poll (call graph
# of the Thumb-2 disassembly), and where the IO8's and the PAM's code
# goes by source module (the same builds with debug info, attributed with
# arm-none-eabi-addr2line -i by examples/firmware/tools/code_by_module.rs).
# Skipped with a note when the target or the arm-none-eabi binutils are
# missing (.ci/run installs both).
#
# Needs the Rust toolchain, gcc and binutils (nm, size, objdump). Figures
# are printed, not asserted: the script fails only when a build fails.
# A harness run that does not reach every state prints a WARNING.
#
# Environment: FOOTPRINT_DIR (default target/footprint) for every output,
# used as CARGO_TARGET_DIR too, so the workspace's target/ is not touched.
set -euo pipefail

cd "$(dirname "$0")/.."
ROOT=$(pwd)
OUT=${FOOTPRINT_DIR:-$ROOT/target/footprint}
case "$OUT" in /*) ;; *) OUT=$ROOT/$OUT ;; esac
mkdir -p "$OUT"
export CARGO_TARGET_DIR=$OUT

FW=examples/firmware
MANIFEST=$FW/Cargo.toml
HARNESS=$FW/harness.c
CC=${CC:-gcc}
CFLAGS=(-Os -std=c11 -no-pie -Wl,--gc-sections)
DEVICES=(base io8 pam io8-et1100 io8-lan9252)
# Cargo features of each build ("io8-et1100": the IO8 with the ET1100 SPI
# driver of drivers/esc-spi instead of the board's C spi_read/spi_write;
# "io8-lan9252" the same with the LAN9252 driver).
declare -A FEATURES=([base]="" [io8]="io8" [pam]="pam" [io8-et1100]="io8 spi-et1100"
    [io8-lan9252]="io8 spi-lan9252" [io8-min]="io8-minimal" [io8-signed]="io8-signed"
    [io8-nofoe]="io8-no-foe")
# Builds measured for size only: the harness speaks the ET1100's SPI byte
# protocol, not the LAN9252's, so running this one would test nothing.
declare -A SIZE_ONLY=([io8-lan9252]=1)

run() {
    printf '+ %s\n' "$*"
    "$@"
}

fail() {
    echo "footprint: $*" >&2
    exit 1
}

for tool in cargo rustc "$CC" nm size objdump; do
    command -v "$tool" >/dev/null || fail "$tool not found"
done
HOST=$(rustc -vV | sed -n 's/^host: //p')

echo "== Build (host target $HOST; profile.release of $MANIFEST: opt-level \"z\", lto, panic = \"abort\", codegen-units = 1)"
for dev in "${DEVICES[@]}"; do
    features=()
    [ -z "${FEATURES[$dev]}" ] || features=(--features "${FEATURES[$dev]}")
    run cargo build --release --manifest-path "$MANIFEST" "${features[@]}" ||
        fail "cargo build of the $dev firmware failed"
    run cp "$OUT/release/libecat_firmware.a" "$OUT/libfw-$dev.a"
    run "$CC" "${CFLAGS[@]}" -o "$OUT/fw-$dev" "$HARNESS" "$OUT/libfw-$dev.a" ||
        fail "linking the $dev firmware failed"
done

STACK_TOOL=$OUT/stack_estimate
if [ ! -x "$STACK_TOOL" ] || [ "$FW/tools/stack_estimate.rs" -nt "$STACK_TOOL" ]; then
    run rustc --edition 2024 -O -o "$STACK_TOOL" "$FW/tools/stack_estimate.rs" ||
        fail "building the stack estimator failed"
fi
run cargo build --release --manifest-path "$FW/sizes/Cargo.toml" ||
    fail "building the size_of report failed"

echo
echo "== Run the harness (simulated master, stack painting of every fw_poll)"
declare -A RC
for dev in "${DEVICES[@]}"; do
    if [ -n "${SIZE_ONLY[$dev]:-}" ]; then
        echo "  ($dev: size only, not run)"
        RC[$dev]=0
        continue
    fi
    echo "+ $OUT/fw-$dev > $OUT/fw-$dev.log"
    set +e
    "$OUT/fw-$dev" >"$OUT/fw-$dev.log" 2>&1
    RC[$dev]=$?
    set -e
    sed 's/^/    /' "$OUT/fw-$dev.log"
    if [ "${RC[$dev]}" -ne 0 ]; then
        echo "    WARNING: the $dev harness exited with ${RC[$dev]} (figures below may miss paths)"
    fi
done

# Size of an output section (0 if absent).
sec() {
    size -A -d "$1" | awk -v s="$2" '$1 == s { n = $2 } END { print n + 0 }'
}

echo
echo "== Sizes (bytes): firmware = device binary - baseline (harness + empty no_std staticlib)"
echo "+ size -A -d $OUT/fw-{base,io8,pam}"
printf '    %-22s %8s %8s %13s %6s %7s %12s %12s %10s\n' \
    "" text rodata .data.rel.ro data bss "flash total" "static RAM" "eh_frame"
declare -A TEXT RO RELRO DATA BSS EH
for dev in "${DEVICES[@]}"; do
    bin=$OUT/fw-$dev
    TEXT[$dev]=$(($(sec "$bin" .text) + $(sec "$bin" .init) + $(sec "$bin" .fini) + $(sec "$bin" .plt)))
    RO[$dev]=$(sec "$bin" .rodata)
    RELRO[$dev]=$(sec "$bin" .data.rel.ro)
    DATA[$dev]=$(sec "$bin" .data)
    BSS[$dev]=$(sec "$bin" .bss)
    EH[$dev]=$(($(sec "$bin" .eh_frame) + $(sec "$bin" .eh_frame_hdr)))
done
row() { # label text ro relro data bss eh
    printf '    %-22s %8d %8d %13d %6d %7d %12d %12d %10d\n' \
        "$1" "$2" "$3" "$4" "$5" "$6" $(($2 + $3 + $4 + $5)) $(($5 + $6)) "$7"
}
row "harness alone (base)" "${TEXT[base]}" "${RO[base]}" "${RELRO[base]}" "${DATA[base]}" "${BSS[base]}" "${EH[base]}"
for dev in io8 pam io8-et1100 io8-lan9252; do
    row "$dev firmware" \
        $((TEXT[$dev] - TEXT[base])) $((RO[$dev] - RO[base])) $((RELRO[$dev] - RELRO[base])) \
        $((DATA[$dev] - DATA[base])) $((BSS[$dev] - BSS[base])) $((EH[$dev] - EH[base]))
done
# The ET1100 driver's own size: the same IO8 firmware with the driver
# minus with the board's C PDI functions (the C side's byte-level SPI
# model is in the harness, not in these figures).
row "ET1100 driver added" \
    $((${TEXT[io8-et1100]} - ${TEXT[io8]})) $((${RO[io8-et1100]} - ${RO[io8]})) $((${RELRO[io8-et1100]} - ${RELRO[io8]})) \
    $((${DATA[io8-et1100]} - ${DATA[io8]})) $((${BSS[io8-et1100]} - ${BSS[io8]})) $((${EH[io8-et1100]} - ${EH[io8]}))
row "LAN9252 driver added" \
    $((${TEXT[io8-lan9252]} - ${TEXT[io8]})) $((${RO[io8-lan9252]} - ${RO[io8]})) $((${RELRO[io8-lan9252]} - ${RELRO[io8]})) \
    $((${DATA[io8-lan9252]} - ${DATA[io8]})) $((${BSS[io8-lan9252]} - ${BSS[io8]})) $((${EH[io8-lan9252]} - ${EH[io8]}))
cat <<'EOF'
    text: machine code (.text .init .fini .plt). rodata: constants without
    pointers (strings, jump tables, panic locations). .data.rel.ro: constant
    tables that hold pointers (the object dictionary's Object/Entry tables,
    vtables); a microcontroller keeps them in flash like rodata. data/bss:
    initialised / zeroed static RAM (the firmware object is in bss).
    flash total = text + rodata + .data.rel.ro + data; static RAM = data + bss
    (the stack comes on top, below). eh_frame: unwind tables the x86-64
    target always emits, absent from a Cortex-M build, not counted.
    libc's memcpy/memset are called, not linked (shared library).
    Reference (issue): SOES core on x86-64, gcc -Os: ~14.8 KB text, ~1.25 KB bss.
EOF

echo
echo "== Biggest firmware symbols (harness and C runtime symbols left out; LTO inlines most code into the entry points)"
nm -C --radix=d "$OUT/fw-base" | cut -d' ' -f3- | grep -v '^fw_' | sort -u >"$OUT/base.names"
for dev in io8 pam; do
    echo "+ nm -C --size-sort -S -r --radix=d $OUT/fw-$dev | head  # $dev, top 10"
    nm -C --size-sort -S -r --radix=d "$OUT/fw-$dev" |
        awk -v names="$OUT/base.names" '
            BEGIN { while ((getline l < names) > 0) skip[l] = 1 }
            {
                n = $0; sub(/^[^ ]+ [^ ]+ [^ ]+ /, "", n)
                if (n in skip) next
                if (length(n) > 110) n = "..." substr(n, length(n) - 106)
                if (++k <= 10) printf "    %7d %s  %s\n", $2 + 0, $3, n
            }'
done

echo
echo "== Firmware text by module (sum of nm symbol sizes; code LTO inlined into fw_poll / fw_init counts there)"
for dev in io8 pam; do
    echo "  $dev:"
    nm -C -S --radix=d "$OUT/fw-$dev" |
        awk -v names="$OUT/base.names" '
            BEGIN { while ((getline l < names) > 0) skip[l] = 1 }
            $3 ~ /^[tTW]$/ {
                n = $0; sub(/^[^ ]+ [^ ]+ [^ ]+ /, "", n)
                if (n in skip) next
                m = n
                if (m ~ /^</ && index(m, " as ") > 0) {
                    # <Type as Trait>::f: the type path, or the trait for a
                    # generic / primitive type (<&T as core::fmt::Display>).
                    t = substr(m, 2, index(m, " as ") - 2)
                    m = (t ~ /::/) ? t : substr(m, index(m, " as ") + 4)
                }
                sub(/^</, "", m)
                sub(/^&?(mut )?/, "", m)
                split(m, p, "::")
                k = p[1]; if (p[2] != "") k = k "::" p[2]
                sub(/<.*/, "", k)
                s[k] += $2; total += $2
            }
            END {
                for (k in s) printf "%7d  %s\n", s[k], k
                printf "%7d  (total)\n", total
            }' | sort -rn | awk 'NR <= 16 { print "    " $0 }'
done

echo
echo "== Stack of one fw_poll"
for dev in io8 pam; do
    log=$OUT/fw-$dev.log
    echo "  $dev, measured by stack painting (fw_poll runs on a painted stack; bytes it overwrote,"
    echo "  incl. frames reserved by stack probes; over the harness traffic of every phase):"
    grep '^STACK ' "$log" | sed 's/^STACK /      /' || true
    awk '/^STACK_MAX/ { m = $2 } /^STACK_INIT/ { i = $2 }
         END { printf "      => max %s bytes per fw_poll (fw_init: %s bytes)\n", m, i }' "$log"
    if [ "${HOST%%-*}" = x86_64 ]; then
        echo "  $dev, static estimate (call graph of the x86-64 disassembly: frames from push / sub %rsp,"
        echo "  direct calls, tail calls and C calls through the GOT; indirect calls listed):"
        run "$STACK_TOOL" "$OUT/fw-$dev" fw_poll fw_init
    else
        echo "  (static estimate skipped: it reads x86-64 disassembly, host is $HOST)"
    fi
done

echo
echo "== What the RAM and the tables are made of"
run cargo run --quiet --release --manifest-path "$FW/sizes/Cargo.toml"

echo
echo "== Summary (bytes; firmware minus baseline; x86-64)"
for dev in io8 pam; do
    max=$(awk '/^STACK_MAX/ { print $2 }' "$OUT/fw-$dev.log")
    printf '    %-4s text %6d  rodata %5d  .data.rel.ro %6d  data %4d  bss %5d  measured poll stack %6s\n' \
        "$dev" $((TEXT[$dev] - TEXT[base])) $((RO[$dev] - RO[base])) $((RELRO[$dev] - RELRO[base])) \
        $((DATA[$dev] - DATA[base])) $((BSS[$dev] - BSS[base])) "${max:-?}"
done
for dev in io8 pam; do
    [ "${RC[$dev]}" -eq 0 ] || echo "    WARNING: the $dev harness run did not complete (exit ${RC[$dev]})"
done

# ---------------------------------------------------------------------
# Cortex-M4: the same crate, features and profile for thumbv7em-none-eabihf.
ARM_TARGET=thumbv7em-none-eabihf
# io8-min: the IO8 whose description offers neither SDO Information nor
# complete access (feature coe-minimal of io8-example): what the two cost.
# io8-signed: the IO8 requiring Ed25519-signed images (the check's size).
# io8-nofoe: the IO8 without BOOT and FoE (the firmware update's size).
ARM_DEVICES=(base io8 pam io8-lan9252 io8-min io8-signed io8-nofoe)
SYSROOT=$(rustc --print sysroot)
echo
if [ ! -d "$SYSROOT/lib/rustlib/$ARM_TARGET/lib" ]; then
    echo "== Cortex-M4: skipped (rustup target add $ARM_TARGET)"
    exit 0
fi
for tool in arm-none-eabi-gcc arm-none-eabi-size arm-none-eabi-objdump arm-none-eabi-nm; do
    if ! command -v "$tool" >/dev/null; then
        echo "== Cortex-M4: skipped ($tool not found; Debian: gcc-arm-none-eabi binutils-arm-none-eabi)"
        exit 0
    fi
done
ARM_CFLAGS=(-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16 -Os -nostartfiles
    -Wl,--gc-sections -Wl,-e,_start -Wl,-z,noexecstack)
# The firmware is a staticlib linked into a C firmware, which links its C
# library anyway. Rust's precompiled compiler_builtins brings its own
# memcpy and a memset in each of __aeabi_memclr, __aeabi_memclr4 and
# __aeabi_memclr8 (about 1.5 KB, built for speed), and as the first archive
# to define them (weakly) it wins the link. The counted link asks for the
# C library's (newlib-nano's) ones instead: the memory symbols the plain
# link holds are made undefined (-u) before libc is searched, ahead of the
# staticlib. Their code counts in the firmware (the baseline references
# none), as it does in the SOES reference. The plain link is kept
# (fw-<dev>-m4-builtins.elf) and its difference printed as a row.
MEM_SYMS="memcpy memmove memset memcmp bcmp __aeabi_memcpy __aeabi_memcpy4 __aeabi_memcpy8
    __aeabi_memmove __aeabi_memmove4 __aeabi_memmove8 __aeabi_memset __aeabi_memset4
    __aeabi_memset8 __aeabi_memclr __aeabi_memclr4 __aeabi_memclr8"
# Without newlib-nano (Debian: libnewlib-arm-none-eabi) the counted link
# is the plain one, and the script says so.
NANO_SPECS=$(arm-none-eabi-gcc -print-file-name=nano.specs)
c_mem_link() { # plain-elf out-elf staticlib [extra link args...]
    local plain=$1 out=$2 lib=$3
    shift 3
    if [ ! -f "$NANO_SPECS" ]; then
        echo "    NOTE: newlib-nano not found (Debian: libnewlib-arm-none-eabi): the figures keep"
        echo "    compiler_builtins' memory functions"
        run cp "$plain" "$out"
        return
    fi
    local undef=()
    for sym in $(arm-none-eabi-nm "$plain" | awk '{ print $NF }' | sort -u); do
        case " $(echo $MEM_SYMS) " in *" $sym "*) undef+=("-Wl,-u,$sym") ;; esac
    done
    run arm-none-eabi-gcc "${ARM_CFLAGS[@]}" --specs=nano.specs -o "$out" "$FW/cortex_m4.c" \
        "${undef[@]}" -lc "$lib" "$@"
}
echo "== Cortex-M4 build ($ARM_TARGET, the same profile; linked with arm-none-eabi-gcc ${ARM_CFLAGS[*]} $FW/cortex_m4.c;"
echo "   memory functions from the C library, newlib-nano, as a C firmware links them)"
for dev in "${ARM_DEVICES[@]}"; do
    features=()
    [ -z "${FEATURES[$dev]}" ] || features=(--features "${FEATURES[$dev]}")
    run cargo build --release --target "$ARM_TARGET" --manifest-path "$MANIFEST" "${features[@]}" ||
        fail "cargo build of the $dev firmware for $ARM_TARGET failed"
    run cp "$OUT/$ARM_TARGET/release/libecat_firmware.a" "$OUT/libfw-$dev-m4.a"
    run arm-none-eabi-gcc "${ARM_CFLAGS[@]}" -o "$OUT/fw-$dev-m4-builtins.elf" "$FW/cortex_m4.c" \
        "$OUT/libfw-$dev-m4.a" ||
        fail "linking the $dev firmware for the Cortex-M4 failed"
    c_mem_link "$OUT/fw-$dev-m4-builtins.elf" "$OUT/fw-$dev-m4.elf" "$OUT/libfw-$dev-m4.a" ||
        fail "linking the $dev firmware with the C library's memory functions failed"
done
msec() {
    arm-none-eabi-size -A -d "$1" | awk -v s="$2" '$1 == s { n = $2 } END { print n + 0 }'
}
declare -A MTEXT MRO MDATA MBSS
for dev in "${ARM_DEVICES[@]}" io8-builtins pam-builtins; do
    case $dev in
    *-builtins) bin=$OUT/fw-${dev%-builtins}-m4-builtins.elf ;;
    *) bin=$OUT/fw-$dev-m4.elf ;;
    esac
    MTEXT[$dev]=$(msec "$bin" .text)
    MRO[$dev]=$(($(msec "$bin" .rodata) + $(msec "$bin" .ARM.exidx)))
    MDATA[$dev]=$(msec "$bin" .data)
    MBSS[$dev]=$(msec "$bin" .bss)
done
echo
echo "== Cortex-M4 sizes (bytes): firmware = device ELF - baseline (stubs + empty no_std staticlib)"
echo "+ arm-none-eabi-size -A -d $OUT/fw-{base,io8,pam,io8-lan9252,io8-min,io8-signed,io8-nofoe}-m4.elf"
printf '    %-22s %8s %8s %6s %7s %12s %12s\n' "" text rodata data bss "flash total" "static RAM"
mrow() { # label text ro data bss
    printf '    %-22s %8d %8d %6d %7d %12d %12d\n' "$1" "$2" "$3" "$4" "$5" $(($2 + $3 + $4)) $(($4 + $5))
}
mrow "stubs alone (base)" "${MTEXT[base]}" "${MRO[base]}" "${MDATA[base]}" "${MBSS[base]}"
for dev in io8 pam io8-lan9252 io8-min io8-signed io8-nofoe; do
    mrow "$dev firmware" $((MTEXT[$dev] - MTEXT[base])) $((MRO[$dev] - MRO[base])) \
        $((MDATA[$dev] - MDATA[base])) $((MBSS[$dev] - MBSS[base]))
done
mrow "LAN9252 driver added" $((MTEXT[io8-lan9252] - MTEXT[io8])) $((MRO[io8-lan9252] - MRO[io8])) \
    $((MDATA[io8-lan9252] - MDATA[io8])) $((MBSS[io8-lan9252] - MBSS[io8]))
mrow "SDO Info + CA cost" $((MTEXT[io8] - MTEXT[io8-min])) $((MRO[io8] - MRO[io8-min])) \
    $((MDATA[io8] - MDATA[io8-min])) $((MBSS[io8] - MBSS[io8-min]))
mrow "signature check added" $((MTEXT[io8-signed] - MTEXT[io8])) $((MRO[io8-signed] - MRO[io8])) \
    $((MDATA[io8-signed] - MDATA[io8])) $((MBSS[io8-signed] - MBSS[io8]))
mrow "FoE update cost" $((MTEXT[io8] - MTEXT[io8-nofoe])) $((MRO[io8] - MRO[io8-nofoe])) \
    $((MDATA[io8] - MDATA[io8-nofoe])) $((MBSS[io8] - MBSS[io8-nofoe]))
for dev in io8 pam; do
    mrow "$dev, Rust's memcpy..." $((MTEXT[$dev-builtins] - MTEXT[base])) $((MRO[$dev-builtins] - MRO[base])) \
        $((MDATA[$dev-builtins] - MDATA[base])) $((MBSS[$dev-builtins] - MBSS[base]))
done
cat <<'EOF2'
    text: Thumb-2 code. rodata: constants, the object dictionary's tables
    (no .data.rel.ro without dynamic relocations) and .ARM.exidx. data/bss
    as for x86-64. memcpy, memset and memcmp count here, unlike on x86-64:
    newlib-nano's, linked ahead of the staticlib. "Rust's memcpy...": the
    same firmware with those of Rust's compiler_builtins, which a plain
    link of the staticlib takes (fw-<dev>-m4-builtins.elf).
    Reference (issue): SOES with arm-none-eabi-gcc -Os on a Cortex-M4:
    ~10.2 KB code with CoE, ~13.1 KB with FoE and EoE, ~1.7 KB static RAM.
EOF2
echo
echo "== Cortex-M4 stack of one fw_poll (static estimate: call graph of the Thumb-2 disassembly;"
echo "   frames from push / vpush / stmdb / sub sp; bl calls, b tail calls; indirect calls listed)"
declare -A MSTACK
for dev in io8 pam io8-min; do
    echo "  $dev:"
    run "$STACK_TOOL" --thumb "$OUT/fw-$dev-m4.elf" fw_poll fw_init | tee "$OUT/stack-$dev-m4.txt"
    MSTACK[$dev]=$(awk '/^  fw_poll: [0-9]+ bytes on the worst path/ { print $2 }' "$OUT/stack-$dev-m4.txt")
done
echo
echo "== Cortex-M4 code by source module (the same builds with debug info; each instruction"
echo "   counted for the innermost inlined frame in this repository's sources, addr2line -i)"
if command -v arm-none-eabi-addr2line >/dev/null; then
    CODE_TOOL=$OUT/code_by_module
    if [ ! -x "$CODE_TOOL" ] || [ "$FW/tools/code_by_module.rs" -nt "$CODE_TOOL" ]; then
        run rustc --edition 2024 -O -o "$CODE_TOOL" "$FW/tools/code_by_module.rs" ||
            fail "building the code attribution tool failed"
    fi
    for dev in io8 pam; do
        echo "  $dev:"
        CARGO_PROFILE_RELEASE_DEBUG=true CARGO_TARGET_DIR=$OUT/debuginfo \
            run cargo build --quiet --release --target "$ARM_TARGET" --manifest-path "$MANIFEST" \
            --features "${FEATURES[$dev]}" ||
            fail "cargo build of the $dev firmware with debug info failed"
        run arm-none-eabi-gcc "${ARM_CFLAGS[@]}" -o "$OUT/fw-$dev-m4-debuginfo-builtins.elf" "$FW/cortex_m4.c" \
            "$OUT/debuginfo/$ARM_TARGET/release/libecat_firmware.a" ||
            fail "linking the $dev firmware with debug info failed"
        c_mem_link "$OUT/fw-$dev-m4-debuginfo-builtins.elf" "$OUT/fw-$dev-m4-debuginfo.elf" \
            "$OUT/debuginfo/$ARM_TARGET/release/libecat_firmware.a" ||
            fail "linking the $dev firmware with debug info failed"
        run "$CODE_TOOL" "$OUT/fw-$dev-m4-debuginfo.elf" 25
        [ "$dev" != io8 ] || run "$CODE_TOOL" --functions "$OUT/fw-$dev-m4-debuginfo.elf" 25
    done
else
    echo "  skipped (arm-none-eabi-addr2line not found)"
fi
echo
echo "== Summary (bytes; firmware minus baseline; Cortex-M4, thumbv7em-none-eabihf)"
for dev in io8 pam io8-min; do
    printf '    %-4s text %6d  rodata %5d  data %4d  bss %5d  flash %6d  static RAM %5d  poll stack (static) %6s\n' \
        "$dev" $((MTEXT[$dev] - MTEXT[base])) $((MRO[$dev] - MRO[base])) $((MDATA[$dev] - MDATA[base])) \
        $((MBSS[$dev] - MBSS[base])) \
        $((MTEXT[$dev] - MTEXT[base] + MRO[$dev] - MRO[base] + MDATA[$dev] - MDATA[base])) \
        $((MDATA[$dev] - MDATA[base] + MBSS[$dev] - MBSS[base])) "${MSTACK[$dev]:-?}"
done
exit 0
