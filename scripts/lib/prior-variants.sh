# Sourced by the benchmark scripts that compare the relative-pose priors'
# variants (bench-vio-trust.sh, bench-fountain-priors.sh).
#
#   map_prior_variants RUNS DATASET [RUN FLAGS...]
#
# Runs `viosfm run DATASET --out RUNS/default RUN FLAGS...` unless
# RUNS/default/summary.json exists, then maps each variant (no_rpc, paper,
# no_bridging) from the default run's stored features and matches (the
# default's run folder copied to RUNS/VARIANT, its manifest with it, so that
# viosfm takes the copy as its own and re-runs only the mapping), each
# unless its summary.json exists. Logs in RUNS/<name>.log. Needs
# VIOSFM (the viosfm binary).
# PRESET (environment): viosfm run's --preset, default paper (the settings of the
# documented figures); PRESET=realtime runs viosfm's default.
map_prior_variants() {
  local runs=$1 dataset=$2
  shift 2
  mkdir -p "$runs"
  if [ ! -f "$runs/default/summary.json" ]; then
    "$VIOSFM" run "$dataset" --out "$runs/default" --preset "${PRESET:-paper}" "$@" > "$runs/default.log" 2>&1
  fi
  local variant flags
  for variant in no_rpc paper no_bridging; do
    [ -f "$runs/$variant/summary.json" ] && continue
    case $variant in
      no_rpc) flags=(--no-rpc) ;;
      paper) flags=(--prior-weighting paper) ;;
      no_bridging) flags=(--no-bridging) ;;
    esac
    rm -rf "$runs/$variant"
    cp -a "$runs/default" "$runs/$variant"
    "$VIOSFM" run "$dataset" --out "$runs/$variant" --preset "${PRESET:-paper}" "$@" "${flags[@]}" > "$runs/$variant.log" 2>&1
  done
}
