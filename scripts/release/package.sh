#!/bin/sh
# The release archive of one target, as .github/workflows/release.yml
# attaches it and the starter CI's install script and cargo-binstall
# ([package.metadata.binstall] in Cargo.toml) look for it:
#
#   OUTDIR/anholonomy-vVERSION-TARGET.tar.gz          the stripped binary, at the top
#   OUTDIR/anholonomy-vVERSION-TARGET.tar.gz.sha256   "HASH  NAME", as sha256sum -c reads it
#
# usage: package.sh VERSION TARGET BINARY OUTDIR
# Strips a copy with the host's `strip` (the release builds are native, so
# the host's strip understands the binary); without one the binary goes in
# as built.
set -eu
[ $# -eq 4 ] || { echo "usage: $0 VERSION TARGET BINARY OUTDIR" >&2; exit 2; }
version=$1 target=$2 binary=$3 out=$4
name="anholonomy-v$version-$target.tar.gz"
stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
cp "$binary" "$stage/anholonomy"
chmod 755 "$stage/anholonomy"
if command -v strip >/dev/null 2>&1; then
    strip "$stage/anholonomy"
fi
mkdir -p "$out"
tar -czf "$out/$name" -C "$stage" anholonomy
if command -v sha256sum >/dev/null 2>&1; then
    hash=$(sha256sum "$out/$name" | cut -d' ' -f1)
else
    hash=$(shasum -a 256 "$out/$name" | cut -d' ' -f1)
fi
printf '%s  %s\n' "$hash" "$name" >"$out/$name.sha256"
echo "$out/$name"
