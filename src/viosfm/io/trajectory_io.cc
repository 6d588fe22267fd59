#include "viosfm/io/trajectory_io.h"
