/* Wrapper header for bindgen: the Embree 3 API luxtally binds to (build.rs stops on a
   machine with Embree 4 only). */
#include <embree3/rtcore.h>
