# Sourced by the scripts that run the simulated sequences with the realistic
# emulated VIO (bench-vio-trust.sh, bench-presets.sh).
#
#   TRUST_CASES                the default cases, NAME:SCENARIO:DURATION_S:MODE
#   simulate_trust_case OUT NAME SCENARIO DURATION MODE [EXTRA_SIMULATE_FLAGS]
#       simulates OUT/seq/NAME unless it exists (log: OUT/NAME.simulate.log);
#       MODE kf: keyframe-like frames (gaps 0.05-7 s), else a frame rate in Hz
#   trust_rate_flags MODE      prints the `viosfm run` rate flags of MODE
#   metric RUN KEY             a run's summary.json value at the jq path KEY, or -
#   mm VALUE                   metres as millimetres with two decimals (- stays -)
# Needs VIOSFM (the viosfm binary); SEED (environment, default 0) seeds the
# sequences.
TRUST_CASES=(room_kf:room:144:kf two_floors_kf:two_floors:144:kf corridor_kf:corridor:144:kf
             room_10hz:room:40:10 two_floors_10hz:two_floors:40:10 corridor_10hz:corridor:40:10)

simulate_trust_case() {
  local out=$1 name=$2 scenario=$3 duration=$4 mode=$5 extra=${6:-}
  local seq=$out/seq/$name
  [ -d "$seq" ] && return 0
  local sim_flags=(--scenario "$scenario" --duration "$duration" --seed "${SEED:-0}" --vio-profile realistic)
  if [ "$mode" = kf ]; then sim_flags+=(--keyframes --rate 20); else sim_flags+=(--rate "$mode"); fi
  # shellcheck disable=SC2086
  "$VIOSFM" simulate "${sim_flags[@]}" $extra --out "$seq" > "$out/$name.simulate.log" 2>&1
}

trust_rate_flags() {
  if [ "$1" = kf ]; then echo --rate 0; else echo --rate "$1"; fi
}

metric() {
  jq -r "$2 // \"-\"" "$1/summary.json" 2>/dev/null || echo -
}

mm() { awk -v v="$1" 'BEGIN { if (v == "-") print "-"; else printf "%.2f", 1000 * v }'; }
