#include "renderer/gltf_loader.h"

#include <gtest/gtest.h>
