#include "stages/geometry/render.h"
