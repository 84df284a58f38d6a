# shellcheck shell=bash
# The token bucket that shapes an emulated camera link to line rate (docs/benchmarks.md, "The
# shaping's burst"), sourced by scripts/camera-link and scripts/bench-gige-link.
#
# link_burst MTU: the bucket's burst in bytes, eight 1500-byte packets at MTU 1500 (12200) and two
# packets at 9000 (18200): the smallest with which the bucket delivers its rate here; a larger
# burst is not line rate.
link_burst() {
  echo $(($1 == 1500 ? 8 * 1500 + 200 : 2 * $1 + 200))
}
