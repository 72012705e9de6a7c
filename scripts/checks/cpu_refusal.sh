#!/usr/bin/env bash
# Outside CI: an appell built for this machine's CPU (.cargo/config.toml, target-cpu=native),
# run under qemu's user-mode emulation of older CPUs, must stop with exit 2 and a message
# naming the missing extension (src/cpu.rs), not die of an illegal instruction (exit 132).
# Needs qemu-user (Debian: apt-get install qemu-user). Usage: scripts/checks/cpu_refusal.sh [BIN]
set -uo pipefail
cd "$(dirname "$0")/../.."
bin=${1:-target/release/appell}
fail=0
# Nehalem: no AVX; SandyBridge: AVX without AVX2 or FMA; Haswell: AVX2 without AVX-512.
for cpu in Nehalem SandyBridge Haswell; do
    err=$(mktemp)
    qemu-x86_64 -cpu "$cpu" "$bin" fit data/example_recording.mcap \
        --rig configs/rig_example.toml >/dev/null 2>"$err"
    code=$?
    msg=$(grep -v '^qemu-x86_64: warning' "$err")
    rm -f "$err"
    echo "$cpu: exit $code: $msg"
    # A build whose every extension this emulated CPU has runs (exit 0); any other ends in 2.
    if [ "$code" != 0 ] && { [ "$code" != 2 ] || [[ "$msg" != *"which this CPU lacks"* ]]; }; then
        fail=1
    fi
done
exit $fail
