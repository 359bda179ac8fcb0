# Several "hosts" on this one machine for tests and benchmarks that cross a network: network
# namespaces, each server host joined to the learner host by its own veth pair and /24, so a
# link can be delayed or cut on its own. Only addresses inside these namespaces are used.
# Source it; needs root and iproute2.
#
#   netns_check || exit 77          # prints why hosts cannot be made here
#   netns_setup 2                   # NETNS_LEARNER, NETNS_SERVER[1..2], SERVER_ADDRESS[1..2], LEARNER_LINK[1..2]
#   netns_run "${NETNS_SERVER[1]}" cmd...  # runs a command on that host
#   netns_link 2 down|up            # cuts or heals server 2's link (packets dropped silently)
#   netns_delay 1 20                # 20 ms more on the learner -> server 1 direction (tc netem)
#   netns_cleanup                   # kills what runs in the namespaces, deletes them
#
# Subnet 10.213.I.0/24 joins server host I (10.213.I.2) to the learner host (10.213.I.1).

NETNS_TAG="ms$$"
NETNS_LEARNER=""
NETNS_SERVER=()
SERVER_ADDRESS=()
LEARNER_LINK=()
NETNS_ALL=()

netns_check() {
  if [[ $(id -u) != 0 ]]; then echo "network namespaces need root (running as uid $(id -u))"; return 1; fi
  if ! command -v ip > /dev/null; then echo "no 'ip' command (Debian package iproute2)"; return 1; fi
  local probe="${NETNS_TAG}probe" why
  if ! why=$(ip netns add "$probe" 2>&1); then echo "cannot create a network namespace: $why"; return 1; fi
  if ! why=$(ip netns exec "$probe" ip link set lo up 2>&1); then  # e.g. no right to remount /sys
    ip netns del "$probe"
    echo "cannot run a command in a network namespace: $why"
    return 1
  fi
  if ! why=$(ip link add "${NETNS_TAG}p0" type veth peer name "${NETNS_TAG}p1" 2>&1); then
    ip netns del "$probe"
    echo "cannot create a veth pair: $why"
    return 1
  fi
  ip link del "${NETNS_TAG}p0" 2> /dev/null || true
  ip netns del "$probe"
}

netns_run() {
  local ns="$1"
  shift
  ip netns exec "$ns" "$@"
}

netns_setup() {
  local hosts="$1" i
  NETNS_LEARNER="${NETNS_TAG}L"
  ip netns add "$NETNS_LEARNER"
  NETNS_ALL+=("$NETNS_LEARNER")
  ip -n "$NETNS_LEARNER" link set lo up
  for ((i = 1; i <= hosts; i++)); do
    NETNS_SERVER[$i]="${NETNS_TAG}S$i"
    ip netns add "${NETNS_SERVER[$i]}"
    NETNS_ALL+=("${NETNS_SERVER[$i]}")
    ip -n "${NETNS_SERVER[$i]}" link set lo up
    LEARNER_LINK[$i]="${NETNS_TAG}l$i"
    ip link add "${LEARNER_LINK[$i]}" type veth peer name "${NETNS_TAG}s$i"
    ip link set "${LEARNER_LINK[$i]}" netns "$NETNS_LEARNER"
    ip link set "${NETNS_TAG}s$i" netns "${NETNS_SERVER[$i]}"
    ip -n "$NETNS_LEARNER" addr add "10.213.$i.1/24" dev "${LEARNER_LINK[$i]}"
    ip -n "${NETNS_SERVER[$i]}" addr add "10.213.$i.2/24" dev "${NETNS_TAG}s$i"
    ip -n "$NETNS_LEARNER" link set "${LEARNER_LINK[$i]}" up
    ip -n "${NETNS_SERVER[$i]}" link set "${NETNS_TAG}s$i" up
    SERVER_ADDRESS[$i]="10.213.$i.2"
  done
}

# A cut that nothing reports: each end's neighbour entry for the other points at a MAC address
# nobody has, so frames leave and are dropped by the far end, silently (no reset, no
# "unreachable", ARP never asked again), as on a path black-holed between two hosts. Only keepalive
# pings can tell. "up" forgets the bogus entries and ARP finds the real ones.
netns_link() {
  local i="$1" state="$2"
  if [[ $state == down ]]; then
    ip -n "$NETNS_LEARNER" neigh replace "10.213.$i.2" lladdr 02:00:00:00:de:ad dev "${LEARNER_LINK[$i]}" nud permanent
    ip -n "${NETNS_SERVER[$i]}" neigh replace "10.213.$i.1" lladdr 02:00:00:00:de:ad dev "${NETNS_TAG}s$i" nud permanent
  else
    ip -n "$NETNS_LEARNER" neigh del "10.213.$i.2" dev "${LEARNER_LINK[$i]}" 2> /dev/null || true
    ip -n "${NETNS_SERVER[$i]}" neigh del "10.213.$i.1" dev "${NETNS_TAG}s$i" 2> /dev/null || true
  fi
}

# Fails (returns 1, prints why) where the kernel has no sch_netem; the caller then delays otherwise.
netns_delay() {
  local i="$1" ms="$2" why
  if ! why=$(ip netns exec "$NETNS_LEARNER" tc qdisc replace dev "${LEARNER_LINK[$i]}" root netem delay "${ms}ms" 2>&1); then
    echo "tc netem: $why"
    return 1
  fi
}

netns_undelay() {
  ip netns exec "$NETNS_LEARNER" tc qdisc del dev "${LEARNER_LINK[$1]}" root 2> /dev/null || true
}

# Waits up to $3 s until host $1 (a namespace) accepts TCP connections on $2 (address:port).
netns_wait_listening() {
  local ns="$1" address="${2%:*}" port="${2##*:}" deadline=$((SECONDS + $3))
  while ((SECONDS < deadline)); do
    if ip netns exec "$ns" bash -c "exec 3<>/dev/tcp/$address/$port" 2> /dev/null; then return 0; fi
    sleep 0.2
  done
  return 1
}

netns_cleanup() {
  local ns pid
  for ns in "${NETNS_ALL[@]}"; do
    for pid in $(ip netns pids "$ns" 2> /dev/null); do kill -KILL "$pid" 2> /dev/null || true; done
  done
  for ns in "${NETNS_ALL[@]}"; do ip netns del "$ns" 2> /dev/null || true; done
  NETNS_ALL=()
}
