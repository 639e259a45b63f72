#!/usr/bin/env bash
# The test command (README, CI): the system packages, then formatting, lints with warnings
# denied, the documentation with warnings denied, and the whole test suite. The lints and the
# docs use the release profile so they share dependency metadata with the test build. The
# examples are not built as programs: each test suite compiles its example's source and runs
# it against the command line (and clippy checks them as targets); the doctests come last.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cargo fmt --all -- --check
cargo clippy --workspace --all-targets --release -- -D warnings
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --release
cargo test --workspace --release --tests
cargo test --workspace --release --doc
