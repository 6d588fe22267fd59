#include "viosfm/scene/trajectory.h"
