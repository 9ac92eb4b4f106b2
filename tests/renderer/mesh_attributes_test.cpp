#include "renderer/mesh_attributes.h"

#include <gtest/gtest.h>
