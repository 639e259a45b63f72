#!/usr/bin/env bash
# The test command (README, CI): the system packages, then formatting, lints with warnings
# denied, the documentation with warnings denied, and the whole test suite. The lints and the
# docs use the release profile so they share dependency metadata with the test build. The
# example programs are built by the CLI's example tests (`cargo build --workspace --examples`,
# the test build's features, so only the examples themselves compile) and run against the command
# line; the doctests come last.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cargo fmt --all -- --check
cargo clippy --workspace --all-targets --release -- -D warnings
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --release
cargo test --workspace --release --tests
cargo test --workspace --release --doc
