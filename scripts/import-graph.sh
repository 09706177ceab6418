#!/usr/bin/env bash
# Prints the engine's import graph as the architecture test reads it: at each level of engine/src, which
# module names which (paths in `use`, code, types and macro calls, re-exports followed), then the test's
# verdict on import cycles. The test lives in tests/engine/architecture/.
set -euo pipefail
cd "$(dirname "$0")/.."
exec cargo test --workspace --test engine -- \
  architecture::engine_modules_import_no_cycle --exact --nocapture --test-threads=1
