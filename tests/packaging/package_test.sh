#!/usr/bin/env bash
# Builds the Debian packages with CPack from the build tree and checks what a user installs:
# the programs, resources and shaders in the right package, library dependencies filled in by
# dpkg-shlibdeps, man pages, the node's systemd unit and postinst, the studio's valid desktop
# entry and icon, and that the installed layout finds its resources (a run of the installed CLI).
# Usage: package_test.sh BUILD_DIR WITH_STUDIO(ON|OFF)
set -euo pipefail
build=$(readlink -f "$1")
with_studio=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

fail() { echo "package_test: FAIL: $*" >&2; exit 1; }

(cd "$build" && cpack --config CPackConfig.cmake -B "$work/out" >"$work/cpack.log" 2>&1) ||
  { cat "$work/cpack.log"; fail "cpack failed"; }

deb() { ls "$work"/out/"$1"_*.deb 2>/dev/null | head -n1; }
# Listings are read whole before grep -q looks at them: under pipefail, grep -q quitting at its
# first match can kill the writer with SIGPIPE and fail the pipeline (a flaky "lacks" verdict).
expect_file() {  # package, path inside it
  local files
  files=$(dpkg-deb -c "$(deb "$1")" | awk '{print $6}')
  grep -qx "./$2" <<<"$files" || fail "$1 lacks /$2"
}
expect_depends() {  # package, a dependency that must be listed
  local depends
  depends=$(dpkg-deb -f "$(deb "$1")" Depends)
  grep -q "$2" <<<"$depends" || fail "$1 does not depend on $2: $depends"
}

packages=(lumistage-common lumistage-node)
[[ "$with_studio" == ON ]] && packages+=(lumistage-studio)
for p in "${packages[@]}"; do
  [[ -n "$(deb "$p")" ]] || fail "no package $p in $(ls "$work/out")"
  expect_depends "$p" "libc6"
done

expect_file lumistage-common usr/bin/lumistage
expect_file lumistage-common usr/share/lumistage/resources/body/generic_human.glb
expect_file lumistage-common usr/share/lumistage/resources/body/generic_human_fine.glb
expect_file lumistage-common usr/share/lumistage/resources/rigs/reference.yaml
expect_file lumistage-common usr/share/lumistage/shaders/studio_actor.vert
expect_file lumistage-common usr/share/man/man1/lumistage.1.gz
expect_depends lumistage-common libyaml-cpp
expect_file lumistage-node usr/bin/lumistage-node
expect_file lumistage-node usr/lib/systemd/system/lumistage-node@.service
expect_file lumistage-node usr/share/man/man1/lumistage-node.1.gz
expect_depends lumistage-node lumistage-common
node_control=$(dpkg-deb --ctrl-tarfile "$(deb lumistage-node)" | tar -t)
grep -qx './postinst' <<<"$node_control" || fail "lumistage-node has no postinst: $node_control"
common_files=$(dpkg-deb -c "$(deb lumistage-common)")
if grep -q lumistage-node <<<"$common_files"; then
  fail "lumistage-common carries the node's files"
fi

# The man pages are the programs' own --help.
dpkg-deb -x "$(deb lumistage-node)" "$work/root"
dpkg-deb -x "$(deb lumistage-common)" "$work/root"
node_man=$(zcat "$work/root/usr/share/man/man1/lumistage-node.1.gz")
grep -qF -- '\-\-studio' <<<"$node_man" ||
  fail "lumistage-node.1 does not document --studio"
grep -q '^ExecStart=/usr/bin/lumistage-node --node %i' "$work/root/usr/lib/systemd/system/lumistage-node@.service" ||
  fail "the unit does not start /usr/bin/lumistage-node for its instance"

# The installed CLI finds its resources next to itself (share/lumistage), not in the source tree.
out=$(env -u LUMISTAGE_RESOURCE_DIR -u LUMISTAGE_SHADER_DIR "$work/root/usr/bin/lumistage" info) ||
  fail "installed lumistage info failed"
grep -qx "resources: $work/root/usr/share/lumistage/resources" <<<"$out" ||
  fail "the installed CLI does not use its installed resources: $out"
grep -qx "shaders:   $work/root/usr/share/lumistage/shaders" <<<"$out" ||
  fail "the installed CLI does not use its installed shaders: $out"

if [[ "$with_studio" == ON ]]; then
  expect_file lumistage-studio usr/bin/lumistage-studio
  expect_file lumistage-studio usr/share/applications/lumistage-studio.desktop
  expect_file lumistage-studio usr/share/icons/hicolor/scalable/apps/lumistage.svg
  expect_file lumistage-studio usr/share/man/man1/lumistage-studio.1.gz
  expect_depends lumistage-studio libqt6widgets6
  dpkg-deb -x "$(deb lumistage-studio)" "$work/root"
  desktop-file-validate "$work/root/usr/share/applications/lumistage-studio.desktop" ||
    fail "the desktop entry is not valid"
fi
echo "package_test: ok: $(cd "$work/out" && ls *.deb | tr '\n' ' ')"
