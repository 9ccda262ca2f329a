#!/bin/sh
# The studio on Aravis cameras without hardware: the reference virtual studio served as twelve
# GigE Vision cameras on 127.0.1.1-127.0.1.12 (lumistage virtual-cameras), streamed by the studio
# over the real protocol. Runs inside packaging/in-network-namespace.sh, where those loopback
# addresses exist; `./studio demo --aravis` does this. Usage: aravis-demo.sh BUILD_DIR [studio args]
set -eu
build=$1
shift
here=$(dirname "$(readlink -f "$0")")
log=$(mktemp)
"$build/app/lumistage" virtual-cameras --config "$here/../resources/studio/reference.yaml" --frames 30 > "$log" 2>&1 &
server=$!
trap 'kill $server 2>/dev/null || true; rm -f "$log"' EXIT
echo "rendering the virtual studio for its cameras..."
until grep -q serving "$log"; do
  kill -0 $server 2>/dev/null || { cat "$log" >&2; exit 1; }
  sleep 0.2
done
"$build/app/lumistage-studio" --source aravis:127.0.1.1 --rig "$here/../resources/rigs/reference.yaml" "$@"
