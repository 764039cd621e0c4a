#!/usr/bin/env bash
# SciPy LSODA baseline vs studyrun on one paper case (benches/baseline_case.yaml):
# builds studyrun (release), times it, runs benches/scipy_baseline.py on the same case,
# prints both times, their ratio and the agreement of the two results.
#   bash benches/baseline.sh            # the case at the study's tolerances
#   TIGHT=1 bash benches/baseline.sh    # also a studyrun DOPRI5 run at rtol 1e-12 as a reference,
#                                       # to split the difference into each integrator's error
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-.venv/bin/python}
[ -x "$PY" ] || PY=python3
OUT=${OUT:-/tmp/baseline_case.h5}
NPZ=${NPZ:-/tmp/baseline.npz}

cargo build --release --quiet
BIN=target/release/studyrun

echo "== studyrun (DOP853 rtol 1e-8, the default; one thread)"
/usr/bin/time -f "%e %U" -o /tmp/baseline_studyrun.time \
    "$BIN" benches/baseline_case.yaml -o "$OUT" --force -q -j 1
read -r SR_WALL SR_USER < /tmp/baseline_studyrun.time
SR_CASE=$("$PY" -c "import h5py,sys; f=h5py.File(sys.argv[1]); print(f'{f[\"wall_time\"][0]:.3f} {int(f[\"rhs_evals\"][0])}')" "$OUT")
read -r SR_CASE_WALL SR_RHS <<< "$SR_CASE"
echo "studyrun process wall ${SR_WALL} s (user ${SR_USER} s; includes the ideal reference run and the file); case wall ${SR_CASE_WALL} s, ${SR_RHS} RHS evaluations"

REF_ARGS=()
if [ "${TIGHT:-0}" = 1 ]; then
    sed 's/method: dop853, rtol: 1e-8, atol: 1e-12/method: dopri5, rtol: 1e-12, atol: 1e-15/; s/^name: baseline_case/name: baseline_tight/' \
        benches/baseline_case.yaml > /tmp/baseline_tight.yaml
    "$BIN" /tmp/baseline_tight.yaml -o /tmp/baseline_tight.h5 --force -q -j 1
    REF_ARGS=(--reference /tmp/baseline_tight.h5)
fi

echo
echo "== SciPy solve_ivp LSODA (rtol 1e-8, atol 1e-12)"
START=$(date +%s.%N)
"$PY" benches/scipy_baseline.py --out "$NPZ" --compare "$OUT" "${REF_ARGS[@]}" | tee /tmp/baseline_scipy.log
END=$(date +%s.%N)
PY_PROC=$(awk -v a="$START" -v b="$END" 'BEGIN{printf "%.3f", b-a}')
eval "$(grep '^SCIPY_WALL=' /tmp/baseline_scipy.log)"

echo
echo "== times (measured in this run)"
awk -v pw="$SCIPY_WALL" -v pi="$SCIPY_INTEGRATION_WALL" -v pp="$PY_PROC" -v nf="$SCIPY_NFEV" -v ns="$SCIPY_NS_PER_RHS" \
    -v sw="$SR_WALL" -v sc="$SR_CASE_WALL" -v sn="$SR_RHS" 'BEGIN{
  printf "SciPy LSODA : integration %.3f s, integration + output sampling %.3f s, whole process %.3f s; nfev %d, %d ns/RHS\n", pi, pw, pp, nf, ns
  printf "studyrun    : case %.3f s (%d RHS evaluations, %.0f ns/RHS), whole process %.3f s\n", sc, sn, sc/sn*1e9, sw
  printf "ratio SciPy/studyrun: integration / case %.1fx, (integration + sampling) / case %.1fx, process / process %.1fx\n", pi/sc, pw/sc, pp/sw
}'
