// The scene dynsky renders when none is given: a small plaza built in code (no files needed),
// with a mirror sphere, a glossy and a diffuse sphere, a tower block and a wet-looking ground, so
// the sky shows both directly and in reflections.
#pragma once

#include "renderer/scene.h"

namespace dynsky {

Scene make_builtin_scene();

}  // namespace dynsky
