// Complex arithmetic for hsi's compute shaders, in the precision chosen by
// HSI_REAL_DOUBLE (1: double, needs shaderFloat64; 0: float). A complex number is a
// Real2 (x = real part, y = imaginary part).
//
// GLSL has no double-precision log or atan (GLSL.std.450 Log/Atan2 are 32-bit
// only), so the double build carries its own: ln by frexp + the atanh series, atan
// by fdlibm's reduction and polynomial, both to about 1e-16 relative.
#ifndef HSI_COMPLEX_GLSL
#define HSI_COMPLEX_GLSL

#include "hsi_real.glsl"

#if HSI_REAL_DOUBLE
const double kPi = 3.14159265358979323846264338328lf;
const double kHalfPi = 1.57079632679489661923132169164lf;
const double kInv2Pi = 0.159154943091895335768883763373lf;
const double kLn2 = 0.693147180559945309417232121458lf;
const double kSqrtHalf = 0.707106781186547524400844362105lf;
double hsi_nan() { return packDouble2x32(uvec2(0u, 0x7ff80000u)); }

// Natural log of x > 0: x = m 2^e with m in [sqrt(1/2), sqrt(2)), then
// ln m = 2 atanh(s), s = (m - 1)/(m + 1), |s| <= 0.1716, series to s^23.
double hsi_ln(double x) {
  int e;
  double m = frexp(x, e);
  if (m < kSqrtHalf) {
    m *= 2.0lf;
    e -= 1;
  }
  const double s = (m - 1.0lf) / (m + 1.0lf);
  const double s2 = s * s;
  double p = 1.0lf / 23.0lf;
  p = p * s2 + 1.0lf / 21.0lf;
  p = p * s2 + 1.0lf / 19.0lf;
  p = p * s2 + 1.0lf / 17.0lf;
  p = p * s2 + 1.0lf / 15.0lf;
  p = p * s2 + 1.0lf / 13.0lf;
  p = p * s2 + 1.0lf / 11.0lf;
  p = p * s2 + 1.0lf / 9.0lf;
  p = p * s2 + 1.0lf / 7.0lf;
  p = p * s2 + 1.0lf / 5.0lf;
  p = p * s2 + 1.0lf / 3.0lf;
  return double(e) * kLn2 + 2.0lf * s * (1.0lf + s2 * p);
}

// atan(t) for 0 <= t <= 1, as fdlibm's s_atan.c (to 1 ulp): t >= 7/16 is reduced
// about 1/2 or 1 (atan t = atan c + atan((t - c)/(1 + t c)), one division), then
// an odd minimax polynomial of degree 23 in the reduced argument.
double hsi_atan_unit(double t) {
  const bool near_half = t >= 0.4375lf && t < 0.6875lf, near_one = t >= 0.6875lf;
  double x = t;
  if (near_half) x = (2.0lf * t - 1.0lf) / (2.0lf + t);
  if (near_one) x = (t - 1.0lf) / (t + 1.0lf);
  const double z = x * x, w = z * z;
  const double s1 = z * (3.33333333333329318027e-01lf + w * (1.42857142725034663711e-01lf +
                    w * (9.09088713343650656196e-02lf + w * (6.66107313738753120669e-02lf +
                    w * (4.97687799461593236017e-02lf + w * 1.62858201153657823623e-02lf)))));
  const double s2 = w * (-1.99999999998764832476e-01lf + w * (-1.11111104054623557880e-01lf +
                    w * (-7.69187620504482999495e-02lf + w * (-5.83357013379057348645e-02lf +
                    w * -3.65315727442169155270e-02lf))));
  if (!near_half && !near_one) return x - x * (s1 + s2);
  // atan(1/2) and atan(1) = pi/4, each as a double plus the rest.
  const double hi = near_half ? 4.63647609000806093515e-01lf : 7.85398163397448278999e-01lf;
  const double lo = near_half ? 2.26987774529616870924e-17lf : 3.06161699786838301793e-17lf;
  return hi - ((x * (s1 + s2) - lo) - x);
}

// Principal argument in (-pi, pi], as std::arg (0 at the origin).
double hsi_atan2(double y, double x) {
  const double ax = abs(x), ay = abs(y);
  const double hi = max(ax, ay), lo = min(ax, ay);
  double a = hi > 0.0lf ? hsi_atan_unit(lo / hi) : 0.0lf;
  a = ay > ax ? kHalfPi - a : a;
  a = x < 0.0lf ? kPi - a : a;
  return y < 0.0lf ? -a : a;
}
#else
const float kPi = 3.14159265358979323846;
const float kHalfPi = 1.57079632679489661923;
const float kInv2Pi = 0.159154943091895335769;
float hsi_nan() { return uintBitsToFloat(0x7fc00000u); }
float hsi_ln(float x) { return log(x); }
float hsi_atan2(float y, float x) { return (x == 0.0 && y == 0.0) ? 0.0 : atan(y, x); }
#endif

Real2 cmul(Real2 a, Real2 b) { return Real2(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x); }
Real2 cconj(Real2 a) { return Real2(a.x, -a.y); }
Real cabs2(Real2 a) { return a.x * a.x + a.y * a.y; }
Real cabs(Real2 a) { return sqrt(cabs2(a)); }
Real2 cdiv(Real2 a, Real2 b) {
  const Real d = cabs2(b);
  return Real2((a.x * b.x + a.y * b.y) / d, (a.y * b.x - a.x * b.y) / d);
}
Real2 cinv(Real2 b) { return Real2(b.x, -b.y) / cabs2(b); }
// Principal log: ln|z| + i arg z.
Real2 clog(Real2 z) { return Real2(Real(0.5) * hsi_ln(cabs2(z)), hsi_atan2(z.y, z.x)); }
// z / (2 pi i) = -i z / (2 pi).
Real2 div_2pi_i(Real2 z) { return Real2(z.y, -z.x) * kInv2Pi; }

#endif  // HSI_COMPLEX_GLSL
