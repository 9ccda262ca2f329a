#!/bin/sh
# Runs a command in a private network namespace whose loopback also has 127.0.1.1-127.0.1.16,
# so that tests can serve GigE Vision cameras on their own addresses without touching the host's
# network. Root, or unprivileged user namespaces, are needed (unshare).
set -e
if [ "${LUMISTAGE_IN_NETNS:-}" != 1 ]; then
  export LUMISTAGE_IN_NETNS=1
  exec unshare --net --map-root-user "$0" "$@"
fi
ip link set lo up
i=1
while [ $i -le 16 ]; do
  ip addr add "127.0.1.$i/8" dev lo
  i=$((i + 1))
done
exec "$@"
