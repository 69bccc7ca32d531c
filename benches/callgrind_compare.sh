#!/usr/bin/env bash
# Instructions per call of every bench of a bench binary, counted by callgrind, for one or
# more binaries side by side (the same bench source before and after a change, both built
# for x86-64-v3: never run valgrind on a v4 or native build). Usage:
#   benches/callgrind_compare.sh batch|kernel FILTER_REGEX BINARY [BINARY ...]
# Prints `bench  instr/call(bin1)  instr/call(bin2) ...  ratio(last/first)`. The driver of each
# bench (an #[inline(never)] function of the bench file) is found from its id; counts are
# inclusive (callees that were not inlined are counted too).
set -euo pipefail
here=$(dirname "$0")
kind=$1; filter=$2; shift 2
driver() { # bench id -> driver symbol
  local id=$1
  case $kind in
    batch)
      case $id in
        resolve_rgba8/*) echo batch::resolve_rgba8 ;;
        resolve_f32/*) echo batch::resolve_f32 ;;
        resolve_rgba16f/*) echo batch::resolve_f16 ;;
        client_mesh/validate_only) echo batch::validate_only ;;
        client_mesh/*) echo "batch::client_${id#*/}" ;;
        # The MLAB and HT drivers over a DynFramebuffer are one function (the same type):
        # the linker keeps one symbol, the HT one.
        */mlab_per_pixel_dyn/*) echo batch::ht_per_pixel_dyn ;;
        */mlab_batcher_dyn/*) echo batch::ht_batcher_dyn ;;
        *) local n=${id#*/}; echo "batch::${n%%/*}" ;;
      esac ;;
    kernel)
      case $id in
        resolve_rgba8/mlab_scalar/*) echo kernel::resolve_scalar; return ;;
        resolve_rgba8/mlab_lanes/*) echo kernel::resolve_lanes; return ;;
        resolve_rgba8/mlab_lanes_f32/*) echo kernel::resolve_lanes_f32; return ;;
        resolve_rgba8/ht_int*) echo kernel::resolve_ht_int; return ;;
        resolve_rgba8/ht_f32*) echo kernel::resolve_ht_f32; return ;;
        resolve_rgba8/*) echo "?"; return ;; # ht_scalar, ht_lanes: closures, no driver symbol
      esac
      local n=${id#*/}; n=${n%%/*}; n=${n%_paper}
      case $n in
        mlab_scalar) echo kernel::mlab_scalar ;; mlab_lanes) echo kernel::mlab_lanes ;;
        ht_scalar) echo kernel::hybrid_scalar ;; ht_lanes) echo kernel::hybrid_lanes ;;
        mlab_lanes_pixel_major) echo kernel::mlab_lanes_pixel_major ;;
        over_rgba8_scalar) echo kernel::over_scalar ;; over_rgba8_lanes) echo kernel::over_lanes ;;
        *) echo "?" ;;
      esac ;;
  esac
}
ids=$("$1" --bench --list 2>/dev/null | sed -n 's/: benchmark$//p' | grep -E "$filter")
for id in $ids; do
  fn=$(driver "$id")
  line="$id"
  first=
  for bin in "$@"; do
    v=$("$here/callgrind.sh" "$bin" "$id" "$fn" 1 inclusive | sed -n 's/.* = \([0-9.]*\) per element/\1/p')
    line="$line $v"
    [ -z "$first" ] && first=$v
    last=$v
  done
  ratio=$(python3 -c "print(f'{$last/$first:.4f}' if $first else 'nan')")
  echo "$line $ratio"
done
