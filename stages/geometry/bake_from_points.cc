#include "stages/geometry/bake_from_points.h"
