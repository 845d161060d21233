#include "stages/geometry/texel_interp.h"
