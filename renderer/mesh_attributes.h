// Vertex attributes a glTF file may leave out: shading normals and tangent frames.
#pragma once

#include "renderer/scene.h"

namespace dynsky {

// Flat normals, as glTF 2.0 requires when a primitive has no NORMAL (spec 3.7.2.1): every
// triangle gets three vertices of its own (all attributes copied) whose normal is the face's
// geometric normal, cross(p1 - p0, p2 - p0) normalised (counter-clockwise front faces).
// Degenerate triangles get +Z so that every normal stays unit length.
void generate_flat_normals(TriangleMesh& mesh);

// Smooth normals: each vertex gets the sum of its triangles' unnormalised cross products, i.e.
// face normals weighted by triangle area, then normalised. Shared vertices stay shared.
void generate_smooth_normals(TriangleMesh& mesh);

// Per-vertex tangents from the UV set `texcoord` (needs normals). The tangent follows dP/du,
// Gram-Schmidt-orthogonalised against the normal; w is the handedness that makes
// bitangent = cross(normal, tangent.xyz) * w point along -dP/dv, i.e. towards the top of the
// image, which is where glTF normal maps put +Y (and what MikkTSpace-authored TANGENTs encode).
// Each triangle contributes in proportion to its area. Vertices without usable UVs (no UV set,
// or only degenerate UV triangles) get an arbitrary unit tangent perpendicular to the normal, w = 1.
void generate_tangents(TriangleMesh& mesh, int texcoord = 0);

}  // namespace dynsky
