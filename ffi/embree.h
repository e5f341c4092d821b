/* Wrapper header for bindgen: the Embree API luxtally binds to. build.rs defines
   LUXTALLY_EMBREE4 when it found Embree 4. */
#ifdef LUXTALLY_EMBREE4
#include <embree4/rtcore.h>
#else
#include <embree3/rtcore.h>
#endif
