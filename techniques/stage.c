/* stage.c - the timed stages' names (stage.h): what their <stage>_ms columns are called. */
#include "stage.h"

const char *const sb_stage_names[SB_STAGE_COUNT] = {"zpass", "minmax", "cascade", "final", "volumes", "rays",
                                                    "clusters", "pose"};
