#!/usr/bin/env bash
# Builds the libFuzzer targets of fuzz/ (clang; ASan + UBSan) in build-fuzz/ and runs each for
# FUZZ_SECONDS (default 60): the glTF loader, the sky image loader and the photograph import.
# Seeds are made now, in a temporary folder, from ../shared (its small GLB/glTF scenes, sky EXRs
# and crops of its photographs; nothing is copied into the repository); fuzz/regressions/ (inputs
# of past findings) is replayed first. A crash, leak, timeout, out-of-memory or UBSan report fails
# the script; the input is kept as build-fuzz/findings/TARGET-*. docs/testing.md.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
seconds=${FUZZ_SECONDS:-60}
shared=${DYNSKY_SHARED_DIR:-$root/../shared}
targets=(gltf_loader sky_image photo_import)

# -O1 with line tables: libFuzzer's usual build (quick to compile, reports name files and lines).
cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -gline-tables-only -DNDEBUG" -DCMAKE_CXX_COMPILER=clang++ -DDYNSKY_FUZZ=ON \
  >/dev/null
ninja -C build-fuzz -j "$(nproc)" "${targets[@]/#/fuzz_}"

work=$(mktemp -d "${TMPDIR:-/tmp}/dynsky-fuzz-seeds-XXXXXX")
trap 'rm -rf "$work"' EXIT
for t in "${targets[@]}"; do mkdir -p "$work/$t"; done

# Seeds. glTF: every scene file under 64 kB (GLB, or glTF whose buffers are data: URIs or missing),
# and a one-triangle glTF with its buffer inline.
echo '{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0,"translation":[0,1,0]}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]}],"materials":[{}],
"buffers":[{"byteLength":42,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIA"}],
"bufferViews":[{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}],
"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}]}' >"$work/gltf_loader/triangle.gltf"
# A skinned and morphed triangle (two joints, an inverse bind matrix, a weighted target, an
# animated joint) with a sheen and specular-colour material: the posing and layered-BSDF paths.
cat >"$work/gltf_loader/skinned.gltf" <<'SEED'
{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0,1]}],"nodes":[{"mesh":0,"skin":0},{"children":[2]},{"translation":[0,1,0],"rotation":[0,0,0.7071068,0.7071068]},{"mesh":0,"weights":[0.5]}],"meshes":[{"primitives":[{"attributes":{"POSITION":0,"JOINTS_0":2,"WEIGHTS_0":3},"indices":1,"material":0,"targets":[{"POSITION":5}]}],"weights":[1]}],"skins":[{"joints":[1,2],"inverseBindMatrices":4}],"materials":[{"extensions":{"KHR_materials_sheen":{"sheenColorFactor":[1,0.5,0.2],"sheenRoughnessFactor":0.4},"KHR_materials_specular":{"specularFactor":0.7,"specularColorFactor":[2,1,0.5]}}}],"extensionsUsed":["KHR_materials_sheen","KHR_materials_specular"],"buffers":[{"byteLength":308,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAAAAAAAAQAAAAABAAAAAIA/AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAAD8AAAA/AAAAAAAAAAAAAIA/AAAAAAAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAAAAAAIA/AACAPwAAAAAAAAAAAAAAAAAAAAAAAIA/AAAAAAAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAgL8AAAAAAACAPwAAAAAAAAAAAACAPwAAAAAAAAAAAACAPwAAAAAAAAAAAACAPwAAAAAAAIA/AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAA9AQ1P/QENT8="}],"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6},{"buffer":0,"byteOffset":44,"byteLength":12},{"buffer":0,"byteOffset":56,"byteLength":48},{"buffer":0,"byteOffset":104,"byteLength":128},{"buffer":0,"byteOffset":232,"byteLength":36},{"buffer":0,"byteOffset":268,"byteLength":8},{"buffer":0,"byteOffset":276,"byteLength":32}],"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"},{"bufferView":2,"componentType":5121,"count":3,"type":"VEC4"},{"bufferView":3,"componentType":5126,"count":3,"type":"VEC4"},{"bufferView":4,"componentType":5126,"count":2,"type":"MAT4"},{"bufferView":5,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,1],"max":[0,0,1]},{"bufferView":6,"componentType":5126,"count":2,"type":"SCALAR","min":[0],"max":[1]},{"bufferView":7,"componentType":5126,"count":2,"type":"VEC4"}],"animations":[{"samplers":[{"input":6,"output":7,"interpolation":"LINEAR"}],"channels":[{"sampler":0,"target":{"node":2,"path":"rotation"}}]}]}
SEED
# The same with a specular-glossiness and unlit material (their loading and mapping paths).
skinned=$(cat "$work/gltf_loader/skinned.gltf")
sheen_material='"materials":[{"extensions":{"KHR_materials_sheen":{"sheenColorFactor":[1,0.5,0.2],"sheenRoughnessFactor":0.4},"KHR_materials_specular":{"specularFactor":0.7,"specularColorFactor":[2,1,0.5]}}}],"extensionsUsed":["KHR_materials_sheen","KHR_materials_specular"]'
old_material='"materials":[{"extensions":{"KHR_materials_pbrSpecularGlossiness":{"diffuseFactor":[0.5,0.25,0.1,0.8],"specularFactor":[0.2,0.1,0.05],"glossinessFactor":0.7},"KHR_materials_unlit":{}}}],"extensionsUsed":["KHR_materials_pbrSpecularGlossiness","KHR_materials_unlit"]'
printf '%s\n' "${skinned/"$sheen_material"/$old_material}" >"$work/gltf_loader/specgloss-unlit.gltf"
if [[ -d $shared/scenes ]]; then
  find "$shared/scenes" \( -name '*.glb' -o -name '*.gltf' \) -size -64k -exec cp -t "$work/gltf_loader" {} +
fi
# Skies: small half and float EXRs (several compressions) from photographs, and 8-bit PNG/JPEG,
# which the sky loader must refuse. Photographs: reductions and crops of each camera's.
photos=()
if [[ -d $shared/skies ]]; then
  for d in arm_tsi_sgp_20170524 arm_tsi_sgp_20170524_overcast_dusk mobotix_sophia_20200812_morning; do
    p=$(find "$shared/skies/$d/images" -name '*.jpg' 2>/dev/null | sort | sed -n 1p)
    [[ -n $p ]] && photos+=("$p")
  done
fi
i=0
for p in "${photos[@]}"; do
  i=$((i + 1))
  s="$work/sky_image/sky$i"
  oiiotool "$p" --resize 32x32 -d half --compression zip -o "$s-half-zip.exr" \
    --resize 16x16 -d float --compression none -o "$s-float.exr" \
    -d half --compression piz -o "$s-half-piz.exr" -d uint8 -o "$s.png" -o "$s.jpg"
  oiiotool "$p" --fit 160x160 -o "$work/photo_import/photo$i-small.jpg"
  oiiotool "$p" --fit 320x320 --cut 200x200+40+40 -o "$work/photo_import/photo$i-crop.jpg"
  # EXIF orientation (turned before import) and an IPTC caption (a Photoshop APP13 segment, which
  # the reader strips: util/image_input.h), so mutations reach both.
  oiiotool "$p" --fit 160x160 --attrib:type=int Orientation 6 --attrib IPTC:Caption "dynsky fuzz seed" \
    -o "$work/photo_import/photo$i-tagged.jpg"
done

status=0
for t in "${targets[@]}"; do
  bin=build-fuzz/fuzz/fuzz_$t
  mkdir -p "build-fuzz/corpus/$t" build-fuzz/findings
  if compgen -G "fuzz/regressions/$t/*" >/dev/null; then
    echo "fuzz: $t: replaying fuzz/regressions/$t"
    "$bin" fuzz/regressions/$t/* >"$work/$t-regressions.log" 2>&1 || {
      cat "$work/$t-regressions.log"
      status=1
    }
  fi
  echo "fuzz: $t for $seconds s ($(ls "$work/$t" | wc -l) seeds)"
  if ! "$bin" -max_total_time="$seconds" -timeout=30 -rss_limit_mb=2560 -print_final_stats=1 \
    -artifact_prefix="build-fuzz/findings/$t-" "build-fuzz/corpus/$t" "$work/$t" >"$work/$t.log" 2>&1; then
    tail -n 60 "$work/$t.log"
    echo "fuzz: $t FAILED: the input is in build-fuzz/findings/"
    status=1
  fi
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$work/$t.log" | tail -1 || true)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$work/$t.log" | tail -1 || true)
  cov=$(grep -o 'cov: [0-9]*' "$work/$t.log" | tail -1 || true)
  echo "fuzz: $t: ${runs:-?} executions, ${rate:-?}/s, $cov"
done
exit $status
