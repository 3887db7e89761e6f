// SCAFFOLD: replaced by the built-in meshes module.
#include "isochart/builtin.h"

#include "isochart/error.h"

namespace isochart {
std::vector<std::string> builtin_names() { return {"sphere", "torus", "creature", "face"}; }
Mesh make_builtin(const std::string& name) { throw InputError("builtin:" + name, "not available yet"); }
}  // namespace isochart
