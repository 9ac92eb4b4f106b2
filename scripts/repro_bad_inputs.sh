#!/bin/bash
# Issue 12 (input half): reproduces each class of bad input with a dynsky binary, printing its exit
# code and last line (run it with an old and a new build to see the bug and the fix). Memory is
# capped at 3 GB and each run at 10 s, so a huge allocation or a hang shows as bad_alloc or rc=124.
D=$(realpath "${1:?dynsky binary}"); W=$(mktemp -d); cd "$W"
run() { local name=$1; shift; out=$( (ulimit -v 3000000; timeout 10 "$D" "$@") 2>&1 ); rc=$?; echo "[$name] rc=$rc :: $(echo "$out" | grep -v '^\s*$' | tail -1 | cut -c1-200)"; }
printf '\0\0\0\0\0\0\0\0\0\0\x80\x3f\0\0\0\0\0\0\0\0\0\0\x80\x3f\0\0\0\0\0\0\0\0\0\0\0\0' > tri.bin
g() { echo "{\"asset\":{\"version\":\"2.0\"$3},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":$1,\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],\"buffers\":[{\"uri\":\"$2\",\"byteLength\":36}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\",\"min\":[0,0,0],\"max\":[1,1,0]}]}"; }
R="--res 8x6 --spp 1 -q -o $W/out.exr"
g '[{"mesh":0}]' tri.bin > ok.gltf; run ok render ok.gltf $R; rm -f out.*
g '[{"mesh":0}]' tri.bin ",\"extras\":$(python3 -c 'print("["*20000+"1"+"]"*20000)')" > deep.gltf; run deep-json render deep.gltf $R
g '[{"mesh":0,"scale":[0,0,0]}]' tri.bin > s0.gltf; run scale0 render s0.gltf $R
g '[{"children":[1],"scale":[1e200,1e200,1e200]},{"mesh":0,"scale":[1e200,1e200,1e200]}]' tri.bin > s200.gltf; run nested1e200 render s200.gltf $R
mkfifo pipe.bin; g '[{"mesh":0}]' pipe.bin > fifo.gltf; run fifo-uri render fifo.gltf $R
mkdir dir.bin; g '[{"mesh":0}]' dir.bin > dir.gltf; run dir-uri render dir.gltf $R
g '[{"mesh":0}]' ../../../../../../etc/passwd > esc.gltf; run dotdot-uri render esc.gltf $R
oiiotool --pattern constant:color=1,1,1 16x16 3 -d float -o sky.exr
oiiotool --pattern constant:color=1,1,1 16x16 3 -d float --compression none -o raw.exr
python3 - <<'P'
b=bytearray(open('raw.exr','rb').read())
for n in (b'dataWindow\0box2i\0', b'displayWindow\0box2i\0'):
    i=b.find(n)+len(n)+4; b[i:i+16]=(0).to_bytes(4,'little')*2+(29999).to_bytes(4,'little')*2
import struct
p=8
while b[p]!=0:
    e=b.index(0,p); t=b.index(0,e+1); sz=struct.unpack('<i',b[t+1:t+5])[0]; p=t+5+sz
b[p+1:p+1]=bytes(8*(30000-16))
open('huge.exr','wb').write(b)
P
run huge-exr-sky render builtin --sky huge.exr $R
run huge-exr-mask sky procedural --duration 0 --sky-res 16 -o p --mask-image huge.exr
oiiotool --pattern checker 64x64 3 -d uint8 -o a.png; cp a.png a.exr; run png-as-exr-sky sky latlong a.exr -o ll.exr
oiiotool --pattern constant:color=1,1,1 16x16 3 -d float --fill:color=1e35,1e35,1e35 5x5+0+0 -o bright.exr 2>/dev/null; run 1e35-sky sky latlong bright.exr -o ll.exr
oiiotool --pattern checker 640x480 3 -d uint8 -o a.jpg; head -c 1200 a.jpg > cut.jpg; run cut-jpeg sky mask cut.jpg --whole-image -o m.png
oiiotool sky.exr sky.exr --siappend -o parts.exr; run multipart sky latlong parts.exr -o ll2.exr
run threads render builtin --threads -1 $R
run seed render builtin --seed -1 $R
run exposure render builtin --exposure inf $R
run width sky latlong sky.exr --width -2 -o ll3.exr
run res render builtin --res 99999999999x5 -q -o $W/o.exr
run duration animate builtin --sky clear --sky-res 16 --res 8x6 --spp 1 --no-video -q --duration 1e9 -o anim
oiiotool --pattern checker 3000x1 3 -d uint8 -o row.jpg; run odd-jpeg sky import row.jpg -o s.exr
echo "left behind: $(ls $W | tr '\n' ' ')"
