/* A second translation unit that includes hsib.h without the implementation. */
#include "hsib.h"

const char* other_status_name(hsib_status s);
const char* other_status_name(hsib_status s) { return hsib_status_name(s); }
