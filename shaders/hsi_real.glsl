// The shaders' real type in the precision HSI_REAL_DOUBLE selects (1: double, needs
// shaderFloat64; 0: float), for the shaders compiled in both; nothing where it is not
// defined (the fragment shaders, which never see a position or a field).
#ifndef HSI_REAL_GLSL
#define HSI_REAL_GLSL

#ifdef HSI_REAL_DOUBLE
#if HSI_REAL_DOUBLE
#define Real double
#define Real2 dvec2
#define Real4 dvec4
#else
#define Real float
#define Real2 vec2
#define Real4 vec4
#endif
#endif

#endif  // HSI_REAL_GLSL
