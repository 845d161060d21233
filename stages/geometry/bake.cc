#include "stages/geometry/bake.h"
