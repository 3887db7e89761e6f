#pragma once
/// Built-in meshes, usable wherever a file name is ("builtin:NAME"). Deterministic.

#include <string>
#include <vector>

#include "isochart/mesh.h"

namespace isochart {

/// Names accepted by make_builtin: "sphere", "torus", "creature", "face".
std::vector<std::string> builtin_names();

/// Builds a built-in mesh by name (without the "builtin:" prefix). Every mesh is a single
/// edge- and vertex-manifold component, consistently oriented (counter-clockwise seen from
/// outside), without duplicate vertices or slivers, and bitwise identical from call to call.
/// Only positions and faces are set. +y is up.
/// - sphere: closed genus 0, unit radius centred at the origin; a 4× subdivided icosahedron
///   (2562 vertices, 5120 faces).
/// - torus: closed genus 1 around the y axis, radii 1 and 0.4; a 72 × 36 grid (5184 faces).
/// - creature: a smooth closed genus-0 four-legged animal, about 3 × 2.4 × 1 units, head
///   towards +x: head with snout, eyes and two ears, four legs with paws, a tail (~24k faces).
///   An implicit surface polygonized by marching tetrahedra and isotropically remeshed.
/// - face: an open disk (one boundary loop) shaped like a face: a height field over an
///   ellipse 1.6 wide and 2 high in the xy-plane, facing +z (~10k faces).
/// \throw InputError for an unknown name (listing the valid ones).
Mesh make_builtin(const std::string& name);

}  // namespace isochart
