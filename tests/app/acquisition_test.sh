#!/bin/sh
# The whole acquisition path with real processes: a synthetic session is served by virtual GigE
# Vision cameras (lumistage virtual-cameras), streamed and recorded by an Aravis client
# (lumistage stream --record), and the recording must hold exactly the frames that were served;
# then the live cameras feed a camera node and the studio's pipeline (lumistage run), also across
# a power cycle of every camera.
# Run inside packaging/in-network-namespace.sh (it needs the 127.0.1.x loopback addresses).
# Usage: acquisition_test.sh LUMISTAGE_BINARY
set -eu
cli=$1
work=$(mktemp -d)
trap 'kill $server 2>/dev/null || true; rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

"$cli" rig ring --cameras 3 --width 320 --height 240 --out "$work/rig.yaml" > /dev/null
printf 'format: lumistage-studio\nversion: 1\nrig: rig.yaml\nactor:\n  vertices: 2000\nmotion:\n  clip: arm_wave\n  fps: 20\n' > "$work/studio.yaml"
"$cli" synth --config "$work/studio.yaml" --frames 4 --bayer --out "$work/served" > /dev/null 2>&1 || fail "synth"

"$cli" virtual-cameras --session "$work/served" --address 127.0.1.3 --seconds 20 > "$work/server.log" 2>&1 &
server=$!
i=0
until grep -q serving "$work/server.log"; do
  i=$((i + 1)); [ $i -lt 100 ] || fail "virtual cameras did not start: $(cat "$work/server.log")"; sleep 0.1
done

"$cli" stream --rig "$work/served/rig.yaml" --address 127.0.1.3 --fps 20 --seconds 3 --record "$work/recorded" > "$work/stream.log" 2>&1 || fail "stream: $(cat "$work/stream.log")"
cat "$work/stream.log"
# It said how long the disk lasts at the cameras' rate before recording.
grep -q "^recording to $work/recorded: .* free, about [0-9]* min at the cameras' [0-9]* MB/s" "$work/stream.log" || fail "stream did not say how long the disk lasts"
sets=$(($(wc -l < "$work/recorded/index.csv") - 1))
[ "$sets" -ge 20 ] || fail "only $sets frame sets recorded in 3 s at 20 fps"

# Every recorded image (raw PNM, as live recordings are stored) is bit for bit one of the served
# ones, made PNM by the merge that converts a take's files.
grep -q "^image_files: pnm$" "$work/recorded/session.yaml" || fail "the recording is not PNM"
"$cli" session merge "$work/served" --out "$work/served-pnm" --image-files pnm > /dev/null || fail "merge to PNM"
for camera in cam01 cam02 cam03; do
  for recorded in "$work/recorded/$camera"/*.pgm; do
    match=no
    for served in "$work/served-pnm/$camera"/*.pgm; do
      if cmp -s "$recorded" "$served"; then match=yes; break; fi
    done
    [ $match = yes ] || fail "$recorded is none of the served frames"
  done
done

# The recording replays, and a replay recorded again keeps the session's rate (the cameras' 20,
# not the option's default).
"$cli" stream --session "$work/recorded" --replay fast --seconds 5 --record "$work/again" > "$work/replay.log" 2>&1 || fail "replay: $(cat "$work/replay.log")"
grep -q "^cam03 *$sets " "$work/replay.log" || fail "replay did not give $sets frames of cam03: $(cat "$work/replay.log")"
grep -q "^fps: 20$" "$work/again/session.yaml" || fail "the replay was recorded at another rate: $(grep fps "$work/again/session.yaml")"
# The same cameras, live, through a camera-node process into the studio's pipeline.
"$cli" run --rig "$work/served/rig.yaml" --address 127.0.1.3 --frames 20 --seconds 15 > "$work/run.log" 2>&1 || fail "run: $(cat "$work/run.log")"
grep -q "^20 frames in all" "$work/run.log" || fail "the pipeline did not complete 20 frames from live cameras: $(cat "$work/run.log")"
kill $server 2>/dev/null || true
wait $server 2>/dev/null || true

# Every camera power-cycled while the pipeline runs (the server stops for 2 s, then serves again):
# the node opens them again and the pipeline goes on to its frame count, on the same processes.
"$cli" virtual-cameras --session "$work/served" --address 127.0.1.3 --seconds 4 > "$work/server.log" 2>&1 &
server=$!
"$cli" run --rig "$work/served/rig.yaml" --address 127.0.1.3 --frames 100 --seconds 40 > "$work/cycled.log" 2>&1 &
run=$!
wait $server || true
sleep 2
"$cli" virtual-cameras --session "$work/served" --address 127.0.1.3 --seconds 40 > "$work/server.log" 2>&1 &
server=$!
wait $run || fail "run across the cameras' power cycle: $(cat "$work/cycled.log")"
grep -q "lost" "$work/cycled.log" || fail "the cameras were never lost: $(cat "$work/cycled.log")"
grep -q "frames again" "$work/cycled.log" || fail "the node never had frames again: $(cat "$work/cycled.log")"
grep -q "^100 frames in all" "$work/cycled.log" || fail "the pipeline did not go on after the cameras came back: $(cat "$work/cycled.log")"

echo "acquisition: $sets frame sets served, streamed, recorded bit-exact and replayed; 20 frames through the pipeline; 100 across the cameras' power cycle"
