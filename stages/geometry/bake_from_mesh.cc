#include "stages/geometry/bake_from_mesh.h"
