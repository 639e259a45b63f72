#!/usr/bin/env bash
# Builds the README's two Bevy programs (the displacement material's and the indirect light
# plugin's; each is a doctest of quadray-bevy) in a new Cargo project outside the workspace that
# depends on quadray-bevy by path, as another project would: its own lock file, its own profile,
# Bevy built afresh (minutes; not part of the test command). Bevy's features are quadray-bevy's
# own (a project adds winit, audio and the rest as it needs them).
#   scripts/outside-project.sh [DIR]    (DIR: where the project goes; a new temporary one by default)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
dir=${1:-$(mktemp -d)}
project=$dir/quadray-bevy-user
cargo new --quiet --vcs none --name quadray-bevy-user "$project"
{
    grep -m1 '^bevy = ' "$root/crates/quadray-bevy/Cargo.toml"
    echo "quadray-bevy = { path = \"$root/crates/quadray-bevy\" }"
} >>"$project/Cargo.toml"

# A doctest's text from a Rust source's `//!` docs: the first `no_run` block, hidden lines none.
doctest() {
    sed -n '/^\/\/! ```no_run$/,/^\/\/! ```$/p' "$1" | sed '1d;$d' | sed -E 's#^//! ?##'
}
rm "$project/src/main.rs"
mkdir "$project/src/bin"
doctest "$root/crates/quadray-bevy/src/lib.rs" >"$project/src/bin/displacement.rs"
doctest "$root/crates/quadray-bevy/src/gi/mod.rs" >"$project/src/bin/indirect_light.rs"
if grep -q '^# ' "$project"/src/bin/*.rs; then
    echo "error: a README Bevy program has hidden lines; this script takes whole programs" >&2
    exit 1
fi

cd "$project"
start=$(date +%s)
CARGO_TARGET_DIR="$project/target" cargo build --bins
echo "built $(ls src/bin | tr '\n' ' ')in $project in $(($(date +%s) - start)) s," \
    "bevy $(cargo tree -i bevy --depth 0 | head -1 | cut -d' ' -f2), rustc $(rustc --version | cut -d' ' -f2)"
