#include "stages/geometry/point_assign.h"
