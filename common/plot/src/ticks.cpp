#include "tactile/plot/ticks.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace tactile::plot {
namespace {

bool usable(double lo, double hi) {
  return std::isfinite(lo) && std::isfinite(hi) && lo != hi && std::isfinite(hi - lo);
}

// 10^e, correctly rounded for |e| <= 22 (exact powers of ten up to 1e22, one division below 1).
double ten_to(int e) {
  double p = 1;
  for (int i = 0; i < std::abs(e); ++i)
    p *= 10;
  return e >= 0 ? p : 1 / p;
}

// A step m * 10^e, m in {1, 2, 5}. Tick k is (k m) * 10^e, or (k m) / 10^-e below 1: the double
// nearest the decimal value, so 3 * 0.2 gives 0.6 and not 0.6000000000000001.
struct Step {
  int m = 0;
  int e = 0;
  double value() const { return tick(1); }
  double tick(double k) const { return e >= 0 ? k * m * ten_to(e) : k * m / ten_to(-e); }
};

std::vector<double> multiples(double lo, double hi, Step st) {
  std::vector<double> out;
  const double step = st.value();
  const double slack = step * 1e-9;
  const double k0 = std::ceil((lo - slack) / step);
  const double k1 = std::floor((hi + slack) / step);
  if (!(k1 - k0 < 1000)) return out;
  for (double k = k0; k <= k1; k += 1)
    out.push_back(k == 0 ? 0.0 : st.tick(k));
  return out;
}

Step choose_step(double lo, double hi, int target) {
  if (!usable(lo, hi)) return {};
  if (lo > hi) std::swap(lo, hi);
  target = std::clamp(target, 2, 50);
  const double raw = (hi - lo) / target;
  int e = static_cast<int>(std::floor(std::log10(raw)));
  const double norm = raw / std::pow(10.0, e);
  int m = 0;
  if (norm < 1.5) {
    m = 1;
  } else if (norm < 3.5) {
    m = 2;
  } else if (norm < 7.5) {
    m = 5;
  } else {
    m = 1;
    ++e;
  }
  if (std::abs(e) > 300) return {};
  Step st{m, e};
  // Never fewer than 2 ticks inside: step down through 5, 2, 1 times the power of ten.
  for (int guard = 0; guard < 8 && multiples(lo, hi, st).size() < 2; ++guard) {
    if (st.m == 5) {
      st.m = 2;
    } else if (st.m == 2) {
      st.m = 1;
    } else {
      st.m = 5;
      --st.e;
    }
  }
  return st;
}

// "1.500000e+05" -> "1.5e5", "2.000000e-05" -> "2e-5".
std::string tidy_scientific(const char* text) {
  std::string s(text);
  const auto e = s.find('e');
  if (e == std::string::npos) return s;
  std::string mant = s.substr(0, e);
  std::string exp = s.substr(e + 1);
  if (mant.find('.') != std::string::npos) {
    while (!mant.empty() && mant.back() == '0')
      mant.pop_back();
    if (!mant.empty() && mant.back() == '.') mant.pop_back();
  }
  std::string sign;
  if (!exp.empty() && (exp[0] == '+' || exp[0] == '-')) {
    if (exp[0] == '-') sign = "-";
    exp.erase(0, 1);
  }
  while (exp.size() > 1 && exp[0] == '0')
    exp.erase(0, 1);
  return mant + "e" + sign + exp;
}

std::string strip_fraction_zeros(std::string s) {
  if (s.find('.') == std::string::npos) return s;
  while (!s.empty() && s.back() == '0')
    s.pop_back();
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s;
}

}  // namespace

double linear_tick_step(double lo, double hi, int target) {
  const Step st = choose_step(lo, hi, target);
  return st.m == 0 ? 0.0 : st.value();
}

std::vector<double> linear_ticks(double lo, double hi, int target) {
  const Step st = choose_step(lo, hi, target);
  if (st.m == 0) return {};
  return multiples(std::min(lo, hi), std::max(lo, hi), st);
}

std::vector<double> log_ticks(double lo, double hi) {
  if (!usable(lo, hi) || lo <= 0 || hi <= 0) return {};
  if (lo > hi) std::swap(lo, hi);
  const double slack = 1e-9;
  const int e0 = static_cast<int>(std::ceil(std::log10(lo) - slack));
  const int e1 = static_cast<int>(std::floor(std::log10(hi) + slack));
  const int decades = e1 - e0 + 1;
  std::vector<double> out;
  if (decades >= 3) {
    const int every = std::max(1, (decades + 9) / 10);
    for (int e = e0; e <= e1; ++e) {
      if ((e - e0) % every == 0) out.push_back(ten_to(e));
    }
    return out;
  }
  const int f0 = static_cast<int>(std::floor(std::log10(lo)));
  const int f1 = static_cast<int>(std::ceil(std::log10(hi)));
  for (int e = f0; e <= f1; ++e) {
    for (int m : {1, 2, 5}) {
      const double v = Step{m, e}.tick(1);
      if (v >= lo * (1 - slack) && v <= hi * (1 + slack)) out.push_back(v);
    }
  }
  if (out.size() >= 2) return out;
  return linear_ticks(lo, hi, 5);
}

std::string format_tick(double value, double step) {
  if (!std::isfinite(value)) return std::isnan(value) ? "nan" : (value > 0 ? "inf" : "-inf");
  char buf[64];
  const double mag = std::abs(value);
  if (value == 0 || (step > 0 && mag < step * 1e-6)) return "0";
  if (mag >= 1e5 || mag < 1e-3) {
    int digits = 6;
    if (step > 0) {
      // Enough mantissa digits to tell neighbours one step apart.
      const double rel = std::floor(std::log10(mag)) - std::floor(std::log10(step));
      digits = std::clamp(static_cast<int>(rel) + 1, 0, 12);
    }
    std::snprintf(buf, sizeof buf, "%.*e", digits, value);
    return tidy_scientific(buf);
  }
  if (step > 0) {
    const int decimals = std::clamp(static_cast<int>(-std::floor(std::log10(step) + 1e-9)), 0, 12);
    std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
    return strip_fraction_zeros(buf);
  }
  std::snprintf(buf, sizeof buf, "%.6g", value);
  return std::string(buf).find('e') != std::string::npos ? tidy_scientific(buf) : std::string(buf);
}

}  // namespace tactile::plot
