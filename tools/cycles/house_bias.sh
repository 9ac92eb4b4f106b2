#!/bin/bash
# Where dynsky and Cycles differ on the House (issue 13, docs/renderer.md "Cross-check with Cycles"):
#  1. House camera 0, 160x90, 256 spp: medians of dynsky / Cycles over image regions, for a uniform
#     sky and the clear sky, Lambert on both sides (--override-material lambert) direct only and with
#     8 bounces, and the glTF materials with 8 bounces;
#  2. furnace plane: directional albedo of three glTF materials at four view angles, dynsky and
#     Cycles against a quadrature of the glTF spec's BRDF.
# Usage: tools/cycles/house_bias.sh [WORKDIR]   (needs Blender and build/cli/dynsky; BLENDER=...)
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
H=$here/tools/cycles
D=${DYNSKY:-$here/build/cli/dynsky}
B=${BLENDER:-blender}
W=${1:-/tmp/house_bias}
command -v "$B" >/dev/null || { echo "house_bias: Blender ('$B') not installed (scripts/setup.sh --cycles)" >&2; exit 1; }
mkdir -p "$W"
cd "$W"
S=$here/scenes/house/house.gltf
cyc() { "$B" -b -P "$H/render_cycles.py" -- "$@" >/dev/null 2>&1; }

"$B" -b -P "$H/make_test_skies.py" -- "$W" >/dev/null 2>&1
"$B" -b -P "$H/fisheye_to_equirect.py" -- sky_uniform.exr sky_uniform_eq.exr --width 2048 >/dev/null 2>&1
"$D" sky clear --lat 48.8566 --lon 2.3522 --time 2026-06-21T16:00:00Z --sky-res 1024 --out clear.exr >/dev/null
"$B" -b -P "$H/fisheye_to_equirect.py" -- clear.exr clear_eq.exr >/dev/null 2>&1

# name | sky | dynsky depth | Cycles bounces | material override
for c in "unif_lam_direct|sky_uniform|1|0|lambert" "clear_lam_direct|clear|1|0|lambert" \
         "clear_lam|clear|9|8|lambert" "clear_gltf|clear|9|8|none"; do
    IFS='|' read -r name sky depth bounces mat <<<"$c"
    "$D" render "$S" --sky $sky.exr --spp 256 --res 160x90 --max-depth "$depth" --ground-albedo 0 \
        --override-material "$mat" -q --out "dyn_$name.exr"
    cyc --scene "$S" --sky ${sky}_eq.exr --spp 256 --res 160x90 --max-bounces "$bounces" \
        --override-material "$mat" --camera-index 0 --out "cyc_$name.exr"
done

# Furnace planes: base colour, roughness; camera 1 m above, looking at 80, 60, 30, 15 degrees elevation.
/usr/bin/python3 - "$H" <<'PY'
import json, sys
sys.path.insert(0, sys.argv[1])
import make_test_scenes as m
for name, base, rough in (('b25r100', 0.25, 1.0), ('b50r050', 0.5, 0.5), ('b06r015', 0.06, 0.15)):
    g = json.loads(json.dumps(m.plane()))
    g['materials'][0]['pbrMetallicRoughness'].update({'baseColorFactor': [base, base, base, 1], 'roughnessFactor': rough})
    g.pop('cameras', None)
    g['scenes'][0]['nodes'] = [0]
    g['nodes'] = g['nodes'][:1]
    json.dump(g, open('plane_%s.gltf' % name, 'w'))
PY
for m in b25r100 b50r050 b06r015; do
    for e in 80 60 30 15; do
        t=$(/usr/bin/python3 -c "import math; print('%.6f' % (-1 / math.tan(math.radians($e))))")
        "$D" render plane_$m.gltf --sky sky_uniform.exr --ground-albedo 0 --look-at 0,1,0,0,0,"$t" --fov 1 \
            --res 16x16 --spp 1024 -q --out "dyn_${m}_$e.exr"
        cyc --scene plane_$m.gltf --sky sky_uniform_eq.exr --lookat 0,1,0,0,0,"$t",1 --res 16x16 --spp 1024 \
            --out "cyc_${m}_$e.exr"
    done
done

/usr/bin/python3 - <<'PY'
import math, re, subprocess
import numpy as np

def load(p):
    out = subprocess.run(['oiiotool', '--dumpdata', p], capture_output=True, text=True, check=True).stdout
    px, w, h = [], 0, 0
    for mm in re.finditer(r'Pixel \((\d+), (\d+)\):\s*([^\n]*)', out):
        w, h = max(w, int(mm.group(1)) + 1), max(h, int(mm.group(2)) + 1)
        px.append([float(v) for v in mm.group(3).split()[:3]])
    return np.array(px).reshape(h, w, 3).mean(axis=2)

regions = {'house front wall (shade)': (66, 20, 86, 38), 'house ground floor (brick)': (62, 40, 88, 55),
           'garage wall (shade)': (110, 42, 150, 58), 'wet paving (right)': (100, 62, 155, 85),
           'trees': (2, 40, 25, 55), 'sky': (0, 0, 160, 15)}
cases = ['unif_lam_direct', 'clear_lam_direct', 'clear_lam', 'clear_gltf']
ims = {c: (load('dyn_%s.exr' % c), load('cyc_%s.exr' % c)) for c in cases}
print('House camera 0: median dynsky / median Cycles per region')
print('%-28s' % 'region' + ''.join('%18s' % c for c in cases))
for name, (x0, y0, x1, y1) in regions.items():
    print('%-28s' % name + ''.join('%18.3f' % (np.median(d[y0:y1, x0:x1]) / np.median(c[y0:y1, x0:x1]))
                                   for d, c in ims.values()))

def gltf_albedo(base, rough, mu_o, n=400):
    """Directional albedo of the glTF spec BRDF (Appendix B) under a uniform white sky, by quadrature."""
    a2 = max(rough * rough, 1e-3) ** 2
    wo = np.array([math.sqrt(1 - mu_o * mu_o), 0, mu_o])
    th = (np.arange(n) + 0.5) / n * (math.pi / 2)
    ph = (np.arange(2 * n) + 0.5) / (2 * n) * 2 * math.pi
    T, P = np.meshgrid(th, ph, indexing='ij')
    wi = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
    h = wi + wo
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    nh, vh, ni = h[..., 2], np.clip((h * wo).sum(-1), 0, 1), wi[..., 2]
    D = a2 / (math.pi * (nh * nh * (a2 - 1) + 1) ** 2)
    g1 = lambda c: 2 * c / (c + np.sqrt(a2 + (1 - a2) * c * c))
    F = 0.04 + 0.96 * (1 - vh) ** 5
    f = (1 - F) * base / math.pi + F * D * g1(mu_o) * g1(ni) / (4 * mu_o * ni)
    return float((f * ni * np.sin(T)).sum() * (math.pi / 2 / n) * (math.pi / n))

print('\nFurnace plane (uniform sky 1, ground 0): directional albedo')
print('%-22s %5s %10s %10s %10s %12s %12s' % ('base, roughness', 'view', 'glTF spec', 'dynsky', 'Cycles',
                                             'dynsky/spec', 'Cycles/spec'))
for m, base, rough in (('b25r100', .25, 1.0), ('b50r050', .5, .5), ('b06r015', .06, .15)):
    for e in (80, 60, 30, 15):
        d = load('dyn_%s_%d.exr' % (m, e))[4:12, 4:12].mean()
        c = load('cyc_%s_%d.exr' % (m, e))[4:12, 4:12].mean()
        g = gltf_albedo(base, rough, math.cos(math.radians(90 - e)))
        print('%-22s %3d deg %10.4f %10.4f %10.4f %12.3f %12.3f' % ('%.2f, %.2f' % (base, rough), 90 - e, g, d, c,
                                                               d / g, c / g))
PY
