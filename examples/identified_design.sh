#!/usr/bin/env bash
# From an exciting trajectory to a verified controller on identified bounds (docs/identification.md,
# section 6): rc3r excite -> a synthetic log -> rc3r identify -> rc3r design --bounds -> rc3r montecarlo.
# Usage: examples/identified_design.sh [WORKDIR] (default: a new temporary directory). Seeded throughout.
set -euo pipefail
RC3R="${RC3R:-rc3r}"
DIR="${1:-$(mktemp -d)}"
mkdir -p "$DIR" && cd "$DIR"
echo "working in $DIR"
$RC3R excite --robot rr3 --duration 20 --seed 1 --out traj.csv --synthetic-log log.csv
$RC3R identify log.csv --robot rr3 --out id-rr3
$RC3R design --robot rr3 --bounds id-rr3/bounds.toml --rate 1000 --n 10 --duration 2 --out design-rr3
$RC3R montecarlo --config design-rr3/design.toml --n 20 --controllers robust,fbl --duration 2 --out mc-rr3
