// What built this program, as `dynsky --version` says it: "dynsky 0.1.0 (commit abc1234)" (the
// commit left out outside git). Rendered images carry it as their Software field (`render`'s,
// `animate`'s frames), so the frames of a farm with mixed builds tell which made them. Sky files do
// not: they are inputs, hashed by content for resume (a sky made again by another build with the
// same pixels is the same sky).
#pragma once

#include <string>

namespace dynsky {

std::string dynsky_version();

}  // namespace dynsky
