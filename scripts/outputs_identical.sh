#!/usr/bin/env bash
# Checks that two builds of dynsky make the same outputs (a refactoring must not change them):
#   scripts/outputs_identical.sh OLD/dynsky NEW/dynsky [WORK_DIR]
# Runs render, sky clear/procedural/import/predict/evaluate, animate (network, flow and procedural
# models) and compare with small settings in each build, then compares EXR and PNG pixels (idiff)
# and reports (paths normalised; timings.csv skipped: it holds wall-clock times). Needs
# ../shared for the import and evaluation. Exit 0 when everything is identical.
set -u
cd "$(dirname "$0")/.."
OLD=$(realpath "$1"); NEW=$(realpath "$2"); WORK=${3:-$(mktemp -d)}; mkdir -p "$WORK"; WORK=$(realpath "$WORK")
run() {
    local EXE=$1 OUT=$2 S=../shared
    rm -rf "$OUT"; mkdir -p "$OUT"
    "$EXE" render builtin --spp 4 --res 96x64 --out "$OUT/builtin.exr" -q
    "$EXE" sky clear --lat 48.85 --lon 2.35 --time 2026-06-21T12:00:00Z --sky-res 128 --out "$OUT/clear.exr" >/dev/null
    "$EXE" render scenes/house/house.gltf --sky "$OUT/clear.exr" --spp 4 --res 96x64 --out "$OUT/house.exr" -q
    "$EXE" sky procedural --cloud-seed 1 --coverage 0.5 --duration 20 --dt 10 --sky-res 128 --out "$OUT/proc" --quiet
    "$EXE" sky import $S/skies/arm_tsi_sgp_20170524/images/tsi_sgpC1_20170524160000Z.jpg --preset arm-tsi --sky-res 128 \
        --out "$OUT/import.exr" >/dev/null
    "$EXE" sky predict --model networks/models/arm_tsi --steps 3 --in "$OUT/import.exr" --out "$OUT/pred" --quiet
    for m in auto flow procedural; do
        "$EXE" animate scenes/tower/tower.gltf --duration 40 --fps 0.1 --spp 2 --res 64x36 --sky-res 128 --model $m \
            --out "$OUT/anim_$m" --no-video -q
    done
    "$EXE" compare scenes/tower/tower.gltf --spp 2 --res 64x36 --sky-res 128 --out "$OUT/cmp" \
        --time 2026-06-21T16:00:00Z >/dev/null 2>&1
    "$EXE" sky evaluate --model networks/models/arm_tsi --sequence arm-tsi --horizons 1,2 --out "$OUT/eval.md" \
        --histogram "$OUT/hist.png" --quiet
}
run "$OLD" "$WORK/old" 2>"$WORK/old.log"
run "$NEW" "$WORK/new" 2>"$WORK/new.log"
bad=0
# Builds before 2026-12 numbered procedural frames with five digits (frame_00000.exr); now four.
for f in $(cd "$WORK/old" && find . -type f -name '*_0[0-9][0-9][0-9][0-9].*'); do
    mv "$WORK/old/$f" "$WORK/old/$(echo "$f" | sed -E 's/_0([0-9]{4})\./_\1./')"
done
[ -f "$WORK/old/proc/manifest.json" ] && sed -i -E 's/_0([0-9]{4})\./_\1./g' "$WORK/old/proc/manifest.json"
for f in $(cd "$WORK/old" && find . -type f | sort); do
    [ -f "$WORK/new/$f" ] || { echo "missing in new: $f"; bad=1; continue; }
    case "$f" in
        # Images by their pixels: their headers name the build (Software) and the input files' paths.
        *.exr|*.png) idiff -q -fail 0 -failpercent 0 "$WORK/old/$f" "$WORK/new/$f" >/dev/null 2>&1 || { echo "differs: $f"; bad=1; } ;;
        *timings.csv) ;;
        *.md) cmp -s <(sed "s#$WORK/old##g" "$WORK/old/$f") <(sed "s#$WORK/new##g" "$WORK/new/$f") || { echo "differs: $f"; bad=1; } ;;
        *) cmp -s "$WORK/old/$f" "$WORK/new/$f" || { echo "differs: $f"; bad=1; } ;;
    esac
done
[ $bad = 0 ] && echo "identical: $(cd "$WORK/old" && find . -type f | wc -l) files (in $WORK)"
exit $bad
