#!/bin/sh
# Links the firmware against bench/usb_link/memory.x instead of the repository's: rust-lld
# looks for an INCLUDEd script in its working directory first, so it runs from here. For the
# bench's `usb` build while that image is over the 62 KiB budget (bench/src/emu/firmware.rs).
dir=$(dirname "$(readlink -f "$0")")
lld="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin/rust-lld"
cd "$dir" || exit 1
if [ "$1" = "-flavor" ]; then shift 2; fi
exec "$lld" -flavor gnu "$@"
