#!/bin/sh
# Written by `anholonomy init` (anholonomy @VERSION@). Installs anholonomy
# ANHOLONOMY_VERSION into ROOT/bin (default ROOT: .anholonomy), for CI:
#
#   1. nothing to do when ROOT/bin/anholonomy already is that version (the
#      CI cache restored it);
#   2. else the release archive of this platform,
#      ANHOLONOMY_RELEASES/vVERSION/anholonomy-vVERSION-TARGET.tar.gz,
#      checked against its .sha256 file: a mismatch stops here (exit 1);
#   3. else (no archive for this platform, none published, no network to
#      it, or a binary that does not run here) a build from source:
#      cargo install --locked --git ANHOLONOMY_REPO --tag vVERSION
#      (needs cargo and Rust 1.95 or newer; about 15 min on 2 cores).
#
# usage: sh install-anholonomy.sh [ROOT]
set -eu

version="${ANHOLONOMY_VERSION:-@VERSION@}"
repo="${ANHOLONOMY_REPO:-@REPO@}"
releases="${ANHOLONOMY_RELEASES:-$repo/releases/download}"
root="${1:-.anholonomy}"
bin="$root/bin/anholonomy"

say() { printf 'install-anholonomy: %s\n' "$*" >&2; }

# True when FILE runs and is anholonomy $version.
is_wanted() {
    [ -x "$1" ] && [ "$("$1" --version 2>/dev/null)" = "anholonomy $version" ]
}

sha256_of() {
    if command -v sha256sum >/dev/null 2>&1; then
        sha256sum "$1" | cut -d' ' -f1
    else
        shasum -a 256 "$1" | cut -d' ' -f1
    fi
}

# HTTPS or a local file:// mirror only; -f: an HTTP error is a failure.
fetch() {
    curl --proto '=https,file' -fsSL --retry 3 -o "$2" "$1"
}

if is_wanted "$bin"; then
    say "anholonomy $version is already in $root/bin"
    exit 0
fi

case "$(uname -s)-$(uname -m)" in
    Linux-x86_64) target=x86_64-unknown-linux-gnu ;;
    Linux-aarch64 | Linux-arm64) target=aarch64-unknown-linux-gnu ;;
    Darwin-arm64) target=aarch64-apple-darwin ;;
    *) target= ;;
esac

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

if [ -z "$target" ]; then
    say "no release binary for $(uname -s) $(uname -m)"
elif ! command -v curl >/dev/null 2>&1; then
    say "no curl to download the release binary with"
else
    archive="anholonomy-v$version-$target.tar.gz"
    url="$releases/v$version/$archive"
    if fetch "$url" "$tmp/$archive" && fetch "$url.sha256" "$tmp/sum"; then
        want=$(cut -d' ' -f1 <"$tmp/sum")
        got=$(sha256_of "$tmp/$archive")
        if [ "$want" != "$got" ]; then
            say "checksum mismatch for $url: $archive.sha256 says $want, the download is $got"
            exit 1
        fi
        tar -xzf "$tmp/$archive" -C "$tmp" anholonomy
        if is_wanted "$tmp/anholonomy"; then
            mkdir -p "$root/bin"
            mv -f "$tmp/anholonomy" "$bin"
            say "installed $("$bin" --version) from $url"
            exit 0
        fi
        say "the release binary does not run here ($("$tmp/anholonomy" --version 2>&1 | head -n 1))"
    else
        say "could not download $url"
    fi
fi

if ! command -v cargo >/dev/null 2>&1; then
    say "no cargo to build from source with: install Rust (https://rustup.rs)"
    exit 1
fi
say "building anholonomy $version from source: $repo, tag v$version"
cargo install --locked --force --root "$root" --git "$repo" --tag "v$version" anholonomy
if ! is_wanted "$bin"; then
    say "$bin is not anholonomy $version after the build"
    exit 1
fi
say "installed $("$bin" --version) from source"
