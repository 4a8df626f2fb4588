#!/usr/bin/env bash
# Silverbox benchmark (issue 15): output-error fits of the linear, Duffing
# (rho = 2, eta = 0) and generalised (rho, eta free) models on the official
# estimation range, scored on the three official test sets.
#
#   scripts/silverbox.sh            # data from ../shared/data/silverbox (repo cloned next to shared/)
#   SILVERBOX_DIR=/path/to/silverbox NLSDOF=/path/to/nlsdof scripts/silverbox.sh
#   INDEPENDENT=1 PYTHON=/path/to/python scripts/silverbox.sh
#                                   # also score each model file with scipy DOP853
#                                   # (scripts/silverbox_independent.py; numpy, scipy; ~1-2 min)
#
# fit-time chooses its RK4 substeps per sample itself (integration error
# < 1 % of the RMS output error); the table prints them and the ratio.
# Split (0-based, half-open; nonlinear_benchmarks Silverbox()):
#   estimation [40650, 105712); tests: arrow full [100, 40575), arrow without
#   extrapolation [100, 32100), multisine [105712, 127400). Each test is predicted
#   from its input and y[:50] (for the initial state); score = 1000 * RMSE(y[50:]) in
#   mV (the signals are in volts). Needs python3 to tabulate the JSON.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
data="${SILVERBOX_DIR:-$here/../../shared/data/silverbox}"
csv="$data/SNLS80mV.csv"
if [ ! -f "$csv" ]; then
    echo "silverbox.sh: $csv not found (set SILVERBOX_DIR)" >&2
    exit 2
fi
if [ -z "${NLSDOF:-}" ]; then
    (cd "$here/.." && cargo build --release -q -p nlsdof-cli)
    NLSDOF="$(cd "$here/.." && cargo metadata --format-version 1 --no-deps \
        | python3 -c 'import json,sys; print(json.load(sys.stdin)["target_directory"])')/release/nlsdof"
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
for model in linear duffing generalised; do
    "$NLSDOF" fit-time --input "$csv" --input-column V1 --output-column V2 \
        --fs 610.3515625 --range 40650:105712 --model "$model" \
        --test 100:40575 --test 100:32100 --test 105712:127400 \
        --out "$tmp/$model.toml" --json > "$tmp/$model.json"
    if [ "${INDEPENDENT:-0}" = 1 ]; then
        "${PYTHON:-python3}" "$here/silverbox_independent.py" --csv "$csv" \
            --model "$tmp/$model.toml" --json "$tmp/$model.json" \
            --out "$tmp/$model.dop853.json" >&2
    fi
done
python3 - "$tmp" <<'PY'
import json, os, sys
tmp = sys.argv[1]
print("| model | parameters (+ x0, v0) | estimation RMS [mV] | arrow full [mV] | arrow no extrap. [mV] | multisine test [mV] | DOP853 arrow full / no extrap. / multisine [mV] | RK4 substeps (integration error / output error) | fit [s] | status |")
print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |")
for m in ["linear", "duffing", "generalised"]:
    v = json.load(open(f"{tmp}/{m}.json"))
    n = len([p for p in v["free"] if p not in ("x0", "v0")])
    s = [t["score_x1000"] for t in v["tests"]]
    status = v["termination"] + ("" if not v["at_bounds"] else "; at bound: " + ",".join(v["at_bounds"]))
    ind = "not run"
    if os.path.exists(f"{tmp}/{m}.dop853.json"):
        d = json.load(open(f"{tmp}/{m}.dop853.json"))["tests"]
        ind = " / ".join(f"{t['dop853_mV']:.4f}" for t in d)
    i = v["integration"]
    print(f"| {m} | {n} | {1000*v['estimation']['rms']:.4f} | {s[0]:.4f} | {s[1]:.4f} | {s[2]:.4f} | {ind} | {i['substeps']} ({i['ratio']:.4f}) | {v['fit_s']:.2f} | {status} |")
print()
print("Published anchors (mV): polynomial NARX 4.15 (arrow full); SUBNET 1.4 / 0.32 / 0.36; BLA about 13.5.")
for m in ["duffing", "generalised"]:
    v = json.load(open(f"{tmp}/{m}.json"))
    p = v["parameters"]
    print(f"{m}: " + ", ".join(f"{k} = {p[k]:.6g}" for k in ["alpha","delta","beta","rho","kappa","eta","gain","input_offset","output_offset"]))
PY
