// Must not compile: the format library may not use the converter (the include_direction test builds this
// and expects the include to be missing, which is what keeps the layers' direction).
#include "converter/convert/convert.h"
