# shellcheck shell=bash disable=SC2034  # QUICK and OUT are read by the sourcing script
# Sourced by the benchmark scripts (bench_peers.sh, tungsten_vs_lt.sh, vcm_radius_equal_error.sh):
# their shared command line, --quick and --out FILE.
# parse_quick_out NAME ARGS...: sets QUICK (0 or 1) and OUT (the file, or empty); anything else
# is an error naming the script.
parse_quick_out() {
  local name=$1
  shift
  QUICK=0
  OUT=""
  while [ $# -gt 0 ]; do
    case "$1" in
      --quick) QUICK=1 ;;
      --out)
        [ $# -ge 2 ] || { echo "$name: --out needs a file" >&2; exit 2; }
        OUT="$2"
        shift
        ;;
      *) echo "$name: unknown argument '$1' (expected --quick or --out FILE)" >&2; exit 2 ;;
    esac
    shift
  done
}
