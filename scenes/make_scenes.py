#!/usr/bin/env python3
"""Writes scenes/tower/tower.gltf and scenes/house/house.gltf: CC0 Kenney City Kit tiles (copied
from ../shared/scenes/KenneyCityKit) plus geometry of our own (wet ground, a mirror-glass tower,
a reflecting pool, a chrome sphere), each with perspective cameras. Scenes in the spirit of the
paper's Tower and House: sky seen directly and in reflections (glass, metal, water, wet ground).

Run from the repository root:  /usr/bin/python3 scenes/make_scenes.py
Standard library only (json, struct, math, shutil)."""
import json, math, os, shutil, struct

KENNEY_LICENSE = '''# License of the Kenney tiles in this folder

`kenney-*.bin` (geometry from the City Kit tiles' .glb files) and `Textures/colormap.png` are from
Kenney's City Kit, KenneyNL/Starter-Kit-City-Builder @ 48458e6f343d6369ac015c77476eb262b964df2b,
`models/*.glb` (via ../shared/scenes/KenneyCityKit; see its PROVENANCE.md).

License: CC0 1.0 Universal (public domain dedication), as stated upstream: the repository README
says "Sprites and 3D Models (CC0 licensed)"; the repository's MIT LICENSE.md covers its Godot code,
not the models. Credit (not required by CC0): Kenney, www.kenney.nl.
https://creativecommons.org/publicdomain/zero/1.0/
'''

HERE = os.path.dirname(os.path.abspath(__file__))
KENNEY = os.path.normpath(os.path.join(HERE, '..', '..', 'shared', 'scenes', 'KenneyCityKit'))


def read_glb(path):
    data = open(path, 'rb').read()
    magic, version, length = struct.unpack('<III', data[:12])
    assert magic == 0x46546C67, path
    off, doc, binary = 12, None, b''
    while off < length:
        clen, ctype = struct.unpack('<II', data[off:off + 8])
        chunk = data[off + 8:off + 8 + clen]
        if ctype == 0x4E4F534A:
            doc = json.loads(chunk)
        elif ctype == 0x004E4942:
            binary = chunk
        off += 8 + clen
    return doc, binary


class Builder:
    def __init__(self, folder):
        self.folder = folder
        self.doc = {'asset': {'version': '2.0', 'generator': 'dynsky scenes/make_scenes.py'},
                    'scene': 0, 'scenes': [{'nodes': []}], 'nodes': [], 'meshes': [], 'materials': [],
                    'accessors': [], 'bufferViews': [], 'buffers': [], 'cameras': [], 'textures': [],
                    'images': [], 'samplers': []}
        self.own = bytearray()
        self.own_buffer = None
        self.tiles = {}
        self.extensions = set()

    # --- Kenney tiles, merged with index offsets -------------------------------------------
    def tile_mesh(self, name):
        if name in self.tiles:
            return self.tiles[name]
        doc, binary = read_glb(os.path.join(KENNEY, name + '.glb'))
        d = self.doc
        off = {k: len(d[k]) for k in ('accessors', 'bufferViews', 'buffers', 'meshes', 'materials',
                                      'textures', 'images', 'samplers')}
        binname = 'kenney-' + name + '.bin'
        open(os.path.join(self.folder, binname), 'wb').write(binary)
        d['buffers'].append({'uri': binname, 'byteLength': len(binary)})
        for bv in doc.get('bufferViews', []):
            bv = dict(bv); bv['buffer'] = off['buffers']; d['bufferViews'].append(bv)
        for a in doc.get('accessors', []):
            a = dict(a)
            if 'bufferView' in a: a['bufferView'] += off['bufferViews']
            d['accessors'].append(a)
        for s in doc.get('samplers', []): d['samplers'].append(s)
        for im in doc.get('images', []): d['images'].append(dict(im))
        for t in doc.get('textures', []):
            t = dict(t)
            if 'source' in t: t['source'] += off['images']
            if 'sampler' in t: t['sampler'] += off['samplers']
            d['textures'].append(t)
        for m in doc.get('materials', []):
            m = json.loads(json.dumps(m))
            pbr = m.get('pbrMetallicRoughness', {})
            if 'baseColorTexture' in pbr: pbr['baseColorTexture']['index'] += off['textures']
            d['materials'].append(m)
        for ext in doc.get('extensionsUsed', []): self.extensions.add(ext)
        for me in doc['meshes']:
            me = json.loads(json.dumps(me))
            for p in me['primitives']:
                p['attributes'] = {k: v + off['accessors'] for k, v in p['attributes'].items()}
                if 'indices' in p: p['indices'] += off['accessors']
                if 'material' in p: p['material'] += off['materials']
            d['meshes'].append(me)
        mesh = off['meshes'] + doc['nodes'][doc['scenes'][doc.get('scene', 0)]['nodes'][0]]['mesh']
        self.tiles[name] = mesh
        return mesh

    def place(self, name, x, z, scale=10.0, yaw_deg=0.0, y=0.0):
        q = [0.0, math.sin(math.radians(yaw_deg) / 2), 0.0, math.cos(math.radians(yaw_deg) / 2)]
        self.node({'name': name, 'mesh': self.tile_mesh(name), 'translation': [x, y, z], 'rotation': q,
                   'scale': [scale, scale, scale]})

    def node(self, n):
        self.doc['nodes'].append(n)
        self.doc['scenes'][0]['nodes'].append(len(self.doc['nodes']) - 1)

    # --- our own geometry ------------------------------------------------------------------
    def material(self, name, color, metallic, roughness):
        self.doc['materials'].append({'name': name, 'pbrMetallicRoughness': {
            'baseColorFactor': list(color) + [1.0], 'metallicFactor': metallic, 'roughnessFactor': roughness}})
        return len(self.doc['materials']) - 1

    def _view(self, payload, target):
        while len(self.own) % 4: self.own.append(0)
        start = len(self.own)
        self.own += payload
        self.doc['bufferViews'].append({'buffer': -1, 'byteOffset': start, 'byteLength': len(payload), 'target': target})
        return len(self.doc['bufferViews']) - 1

    def mesh(self, name, positions, normals, indices, material):
        pv = self._view(struct.pack('<%df' % (3 * len(positions)), *[c for p in positions for c in p]), 34962)
        nv = self._view(struct.pack('<%df' % (3 * len(normals)), *[c for p in normals for c in p]), 34962)
        iv = self._view(struct.pack('<%dI' % len(indices), *indices), 34963)
        a = self.doc['accessors']
        lo = [min(p[k] for p in positions) for k in range(3)]
        hi = [max(p[k] for p in positions) for k in range(3)]
        a.append({'bufferView': pv, 'componentType': 5126, 'count': len(positions), 'type': 'VEC3', 'min': lo, 'max': hi})
        a.append({'bufferView': nv, 'componentType': 5126, 'count': len(normals), 'type': 'VEC3'})
        a.append({'bufferView': iv, 'componentType': 5125, 'count': len(indices), 'type': 'SCALAR'})
        n = len(a)
        self.doc['meshes'].append({'name': name, 'primitives': [
            {'attributes': {'POSITION': n - 3, 'NORMAL': n - 2}, 'indices': n - 1, 'material': material}]})
        self.node({'name': name, 'mesh': len(self.doc['meshes']) - 1})

    def box(self, name, lo, hi, material):
        P, N, I = [], [], []
        for axis in range(3):
            for sign in (-1, 1):
                u, v = [(axis + 1) % 3, (axis + 2) % 3]
                base = len(P)
                for a, b in ((0, 0), (1, 0), (1, 1), (0, 1)):
                    p = [0, 0, 0]
                    p[axis] = hi[axis] if sign > 0 else lo[axis]
                    p[u] = hi[u] if a else lo[u]
                    p[v] = hi[v] if b else lo[v]
                    P.append(p)
                    n = [0, 0, 0]; n[axis] = sign; N.append(n)
                I += [base, base + 1, base + 2, base, base + 2, base + 3] if sign > 0 else [base, base + 2, base + 1, base, base + 3, base + 2]
        self.mesh(name, P, N, I, material)

    def sphere(self, name, centre, radius, material, rings=48, segments=96):
        P, N, I = [], [], []
        for r in range(rings + 1):
            th = math.pi * r / rings
            for s in range(segments + 1):
                ph = 2 * math.pi * s / segments
                n = [math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph)]
                N.append(n); P.append([centre[k] + radius * n[k] for k in range(3)])
        for r in range(rings):
            for s in range(segments):
                a, b = r * (segments + 1) + s, (r + 1) * (segments + 1) + s
                I += [a, a + 1, b, a + 1, b + 1, b]
        self.mesh(name, P, N, I, material)

    def camera(self, name, eye, target, yfov_deg=50.0, aspect=16 / 9):
        f = [target[k] - eye[k] for k in range(3)]
        fl = math.sqrt(sum(c * c for c in f)); f = [c / fl for c in f]
        up = [0, 1, 0]
        r = [f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]]
        rl = math.sqrt(sum(c * c for c in r)); r = [c / rl for c in r]
        u = [r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]]
        z = [-c for c in f]
        m = [[r[0], u[0], z[0]], [r[1], u[1], z[1]], [r[2], u[2], z[2]]]  # columns: right, up, back
        tr = m[0][0] + m[1][1] + m[2][2]
        if tr > 0:
            s = math.sqrt(tr + 1.0) * 2
            q = [(m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, 0.25 * s]
        elif m[0][0] > m[1][1] and m[0][0] > m[2][2]:
            s = math.sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2
            q = [0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s, (m[2][1] - m[1][2]) / s]
        elif m[1][1] > m[2][2]:
            s = math.sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2
            q = [(m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s, (m[0][2] - m[2][0]) / s]
        else:
            s = math.sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2
            q = [(m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s, (m[1][0] - m[0][1]) / s]
        self.doc['cameras'].append({'name': name, 'type': 'perspective', 'perspective': {
            'yfov': math.radians(yfov_deg), 'aspectRatio': aspect, 'znear': 0.1, 'zfar': 2000.0}})
        self.node({'name': name, 'camera': len(self.doc['cameras']) - 1, 'translation': list(eye), 'rotation': q})

    def write(self, name):
        own_index = len(self.doc['buffers'])
        binname = name + '.bin'
        open(os.path.join(self.folder, binname), 'wb').write(bytes(self.own))
        self.doc['buffers'].append({'uri': binname, 'byteLength': len(self.own)})
        for bv in self.doc['bufferViews']:
            if bv['buffer'] == -1: bv['buffer'] = own_index
        if self.extensions: self.doc['extensionsUsed'] = sorted(self.extensions)
        for k in [k for k, v in self.doc.items() if v == []]: del self.doc[k]
        if self.tiles:
            os.makedirs(os.path.join(self.folder, 'Textures'), exist_ok=True)
            shutil.copy(os.path.join(KENNEY, 'Textures', 'colormap.png'), os.path.join(self.folder, 'Textures', 'colormap.png'))
            with open(os.path.join(self.folder, 'KENNEY_LICENSE.md'), 'w') as f:
                f.write(KENNEY_LICENSE)
        with open(os.path.join(self.folder, name + '.gltf'), 'w') as f:
            json.dump(self.doc, f, indent=1)


def tower():
    b = Builder(os.path.join(HERE, 'tower'))
    os.makedirs(b.folder, exist_ok=True)
    wet = b.material('wet asphalt', (0.04, 0.04, 0.045), 0.0, 0.12)
    glass = b.material('mirror glass facade', (0.55, 0.66, 0.72), 1.0, 0.03)
    frame = b.material('steel frame', (0.55, 0.56, 0.58), 1.0, 0.35)
    water = b.material('pool water', (0.01, 0.02, 0.025), 0.0, 0.0)
    stone = b.material('pool rim stone', (0.55, 0.53, 0.5), 0.0, 0.8)
    chrome = b.material('chrome', (0.95, 0.95, 0.95), 1.0, 0.02)
    b.box('ground', (-400, -0.2, -400), (400, 0.0, 400), wet)
    b.box('tower glass', (-8, 0, -8), (8, 70, 8), glass)
    for y in range(0, 71, 10):  # floor bands: scale cues in the reflections
        b.box('tower band %d' % y, (-8.15, y - 0.25, -8.15), (8.15, y + 0.25, 8.15), frame)
    b.box('pool rim', (-14, 0.0, 13), (14, 0.35, 33), stone)
    b.box('pool water', (-13, 0.0, 14), (13, 0.3, 32), water)
    b.sphere('chrome sphere', (17, 2.5, 22), 2.5, chrome)
    for i, (name, x, z, yaw) in enumerate([('building-small-a', -30, -5, 90), ('building-small-b', -30, 8, 90),
                                            ('building-small-c', 30, -5, -90), ('building-small-d', 30, 8, -90),
                                            ('building-garage', -30, 21, 90), ('building-small-a', 30, 21, -90),
                                            ('grass-trees-tall', -20, 40, 0), ('grass-trees', 20, 40, 0),
                                            ('pavement-fountain', 0, 46, 0)]):
        b.place(name, x, z, 10.0, yaw)
    for z in range(-30, 70, 10):
        b.place('road-straight-lightposts' if z % 20 == 0 else 'road-straight', -44, z, 10.0, 0)
        b.place('road-straight', 44, z, 10.0, 0)
    b.camera('Tower: looking up from the pool', (6, 1.8, 62), (0, 22, 0), 55)
    b.camera('Tower: wide', (45, 12, 75), (0, 18, 5), 50)
    b.write('tower')


def house():
    b = Builder(os.path.join(HERE, 'house'))
    os.makedirs(b.folder, exist_ok=True)
    wet = b.material('wet paving', (0.06, 0.06, 0.06), 0.0, 0.15)
    water = b.material('pond water', (0.01, 0.02, 0.02), 0.0, 0.0)
    stone = b.material('pond rim', (0.5, 0.48, 0.45), 0.0, 0.85)
    chrome = b.material('chrome', (0.95, 0.95, 0.95), 1.0, 0.02)
    roof = b.material('metal roof', (0.7, 0.72, 0.75), 1.0, 0.25)
    b.box('ground', (-300, -0.2, -300), (300, 0.0, 300), wet)
    b.place('building-small-b', 0, 0, 12.0, 0)
    b.box('metal canopy', (-6.5, 5.0, 6.0), (6.5, 5.25, 9.5), roof)
    b.box('canopy post l', (-6.3, 0, 9.2), (-6.0, 5.0, 9.5), roof)
    b.box('canopy post r', (6.0, 0, 9.2), (6.3, 5.0, 9.5), roof)
    b.box('pond rim', (-7, 0.0, 13), (5, 0.3, 21), stone)
    b.box('pond water', (-6.5, 0.0, 13.5), (4.5, 0.25, 20.5), water)
    b.sphere('garden sphere', (8, 1.2, 16), 1.2, chrome)
    b.place('building-garage', 16, -2, 10.0, -90)
    b.place('grass-trees-tall', -16, 2, 10.0, 0)
    b.place('grass-trees', -16, 16, 10.0, 0)
    b.place('building-small-c', -20, -22, 10.0, 0)
    b.place('building-small-d', 12, -24, 10.0, 0)
    for x in range(-40, 50, 10):
        b.place('road-straight', x, 32, 10.0, 90)
    b.camera('House: from the garden', (12, 1.6, 30), (0, 5, 2), 55)
    b.camera('House: pond reflection', (-2, 1.2, 27), (-1, 3.5, 0), 60)
    b.write('house')


if __name__ == '__main__':
    tower()
    house()
    print('wrote scenes/tower/tower.gltf and scenes/house/house.gltf')
