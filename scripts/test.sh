#!/usr/bin/env bash
# The test command (README, CI): the system packages, then formatting, the documentation with
# warnings denied, and the whole test suite built with clippy as the workspace's compiler, so the
# lints (warnings and clippy's defaults denied in Cargo.toml) come with the one build of the tests
# instead of a second, check-only build of every dependency.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cargo fmt --all -- --check
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --release
clippy=$(command -v clippy-driver) || {
    echo "test.sh: clippy-driver is missing: rustup component add clippy" >&2
    exit 1
}
RUSTC_WORKSPACE_WRAPPER=$clippy cargo test --workspace --release
