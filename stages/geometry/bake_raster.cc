#include "stages/geometry/bake_raster.h"
