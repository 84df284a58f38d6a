# shellcheck shell=bash
# IPv4 addresses as integers, for network arithmetic in the scripts (scripts/run-system's
# --host-net, scripts/run-compose's choice of networks).

# ip_to_int A.B.C.D: the address as an integer.
ip_to_int() {
  local IFS=.
  # shellcheck disable=SC2086
  set -- $1
  echo $((($1 << 24) | ($2 << 16) | ($3 << 8) | $4))
}

# int_to_ip N: the integer as A.B.C.D.
int_to_ip() { echo "$((($1 >> 24) & 255)).$((($1 >> 16) & 255)).$((($1 >> 8) & 255)).$(($1 & 255))"; }
