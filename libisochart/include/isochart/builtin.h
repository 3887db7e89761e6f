#pragma once
/// Built-in meshes, usable wherever a file name is ("builtin:NAME"). Deterministic.

#include <string>
#include <vector>

#include "isochart/mesh.h"

namespace isochart {

/// Names accepted by make_builtin: "sphere", "torus", "creature", "face".
std::vector<std::string> builtin_names();

/// Builds a built-in mesh by name (without the "builtin:" prefix).
/// - sphere: closed genus 0, unit radius.
/// - torus: closed genus 1.
/// - creature: a smooth closed genus-0 body with head, ears, four legs and a tail.
/// - face: an open disk-topology patch shaped like a face (one boundary loop).
/// \throw InputError for an unknown name (listing the valid ones).
Mesh make_builtin(const std::string& name);

}  // namespace isochart
