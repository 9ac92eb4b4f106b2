#!/bin/bash
# Error per spp of the two sample patterns (--sampler-pattern random|sobol) on the House and the
# spheres: relative MSE against a random 2048 spp reference, untrimmed and without the 0.1 % worst
# pixels (issue 13's measure). Usage: bench/sample_pattern_error.sh [OUT_DIR] (needs ../shared).
set -euo pipefail
case ${1:-} in
    -h | --help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    -*) echo "sample_pattern_error: unknown option '$1' (usage: $0 [OUT_DIR]; --help)" >&2; exit 2 ;;
esac
here=$(cd "$(dirname "$0")/.." && pwd)
D=$here/build/cli/dynsky
out=${1:-/tmp/sample_pattern_error}
mkdir -p "$out"
metric() {  # untrimmed and trimmed relative MSE of $1 against $2
    python3 - "$1" "$2" <<'PY'
import re, subprocess, sys
def load(p):
    out = subprocess.run(['oiiotool', '--dumpdata', p], capture_output=True, text=True, check=True).stdout
    return [[float(v) for v in m.group(1).split()[:3]] for m in re.finditer(r'Pixel \(\d+, \d+\):\s*([^\n]*)', out)]
a, r = load(sys.argv[1]), load(sys.argv[2])
per = sorted(sum((x - y) ** 2 / (y * y + 0.01) for x, y in zip(pa, pr)) / 3 for pa, pr in zip(a, r))
n = len(per); k = max(1, n // 1000)
print('%.5f %.5f' % (sum(per) / n, sum(per[:n - k]) / (n - k)))
PY
}
echo "scene spp pattern relMSE relMSE_trimmed"
for scene in house:$here/scenes/house/house.gltf \
             spheres:$here/../shared/scenes/MetalRoughSpheresNoTextures/MetalRoughSpheresNoTextures.glb; do
    name=${scene%%:*} path=${scene#*:}
    "$D" render "$path" --res 128x72 --spp 2048 --seed 777 -q --out "$out/${name}_ref.exr"
    for spp in 4 16 64; do
        for pattern in random sobol; do
            "$D" render "$path" --res 128x72 --spp $spp --sampler-pattern $pattern -q --out "$out/${name}_${pattern}_$spp.exr"
            echo "$name $spp $pattern $(metric "$out/${name}_${pattern}_$spp.exr" "$out/${name}_ref.exr")"
        done
    done
done
