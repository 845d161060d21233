#include "stages/metrics/fps_model.h"
