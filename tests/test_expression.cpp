#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "solver/expression.hpp"
#include "solver/vector_math.hpp"
#include "basis/core/input_error.hpp"

using namespace knotwork;

TEST_CASE("Expressions evaluate with the documented functions and constants", "[expression]") {
  ExpressionEvaluator e(Expression::parse("sin(pi*x)*exp(y) + log(e) + atan2(y, x) + x^2", "test"));
  const double x = 0.3, y = -0.7;
  REQUIRE(std::abs(e(x, y) - (std::sin(M_PI * x) * std::exp(y) + 1.0 + std::atan2(y, x) + x * x)) < 1e-14);
  ExpressionEvaluator neg(Expression::parse("-x^2", "test"));
  REQUIRE(neg(3, 0) == Approx(-9.0));
}

TEST_CASE("Syntax errors name the place and the character", "[expression]") {
  REQUIRE_THROWS_AS(Expression::parse("sin(x", "case.toml: [problem] exact"), InputError);
  REQUIRE_THROWS_WITH(Expression::parse("sin(x", "case.toml: [problem] exact"),
                      Catch::StartsWith("case.toml: [problem] exact: ") && Catch::Contains("')' is missing"));
  REQUIRE_THROWS_WITH(Expression::parse("x + w", "f"), Catch::Contains("unknown name 'w'") && Catch::Contains("character 5"));
  REQUIRE_THROWS_WITH(Expression::parse("  ", "f"), Catch::Contains("empty"));
  REQUIRE_THROWS_WITH(Expression::parse("2x", "f"), Catch::Contains("2*x"));
  REQUIRE_THROWS_WITH(Expression::parse("min(x, y)", "f"), Catch::Contains("unknown function 'min'"));
  REQUIRE_THROWS_WITH(Expression::parse("atan2(x)", "f"), Catch::Contains("atan2 takes 2 arguments, not 1"));
  REQUIRE_THROWS_WITH(Expression::parse("x > 0.1 ? 1 : -1", "f"), Catch::Contains("unexpected '>'"));
  REQUIRE_THROWS_WITH(Expression::parse("sin + 1", "f"), Catch::Contains("'sin' is a function"));
  REQUIRE_THROWS_WITH(Expression::parse("x*", "f"), Catch::Contains("operand is missing"));
  REQUIRE_THROWS_WITH(Expression::parse("1e999*x", "f"), Catch::Contains("beyond double precision"));
  // Nesting and length are bounded (the tree is walked recursively).
  REQUIRE_THROWS_WITH(Expression::parse(std::string(300, '(') + "x" + std::string(300, ')'), "f"),
                      Catch::Contains("nested deeper"));
  std::string deep_calls = "x";
  for (int i = 0; i < 70; ++i) deep_calls = "sin(" + deep_calls + ")";
  REQUIRE_THROWS_WITH(Expression::parse(deep_calls, "f"), Catch::Contains("calls nested deeper than 64"));
  std::string long_sum = "x";
  while (long_sum.size() < 5000) long_sum += "+x";
  REQUIRE_THROWS_WITH(Expression::parse(long_sum, "f"), Catch::Contains("longer than 4096"));
}

TEST_CASE("The grammar's precedence: ^ binds tightest and to the right, a sign after it to its operand",
          "[expression]") {
  // The values are those of the usual convention (Python's **, muParser), computed by hand.
  const std::pair<const char*, double> cases[] = {
      {"-2^2", -4.0},     {"2^3^2", 512.0},  {"2^-1*3", 1.5},   {"2^-2^2", 1.0 / 16}, {"-2^-2", -0.25},
      {"2*-3", -6.0},     {"--2", 2.0},      {"1e-3*2", 0.002}, {".5 + 3.", 3.5},     {"2^+1*3", 6.0},
      {"8/2/2", 2.0},     {"8-2-2", 4.0},    {"pow(2, 3)", 8.0}, {"sqrt(16)", 4.0},   {"log(e^2)", 2.0}};
  for (const auto& [text, value] : cases) {
    INFO(text);
    ExpressionEvaluator e(Expression::parse(text, "t"));
    REQUIRE(e(0.3, 0.4) == Approx(value).epsilon(1e-15));
  }
  ExpressionEvaluator xy(Expression::parse("x^-2 + 1", "t"));
  REQUIRE(xy(2.0, 0.0) == Approx(1.25).epsilon(1e-15));
}

TEST_CASE("Symbolic derivatives agree with finite differences", "[expression]") {
  for (const char* text : {"sin(pi*x)*sin(pi*y)", "exp(x)*sin(y)", "-(x^2+y^2-1)*(x^2+y^2-4)*x*y^2",
                           "(x^2+y^2)^(1/3)*sin(2/3*(atan2(-y,-x)+pi))", "sqrt(1+x^2)*cosh(y)/(2+sin(x*y))",
                           "abs(x - 0.1)*exp(y) + abs(y)^3"}) {  // abs: GiNaC writes its derivative with conjugates
    INFO(text);
    const ExactSolution ex = differentiate_exact_solution(Expression::parse(text, "t"));
    ExpressionEvaluator u(ex.u), ux(ex.u_x), uy(ex.u_y), f(ex.minus_laplacian);
    for (auto [x, y] : {std::pair{0.31, 0.52}, {-0.45, 0.27}, {0.8, 0.66}}) {
      const double h = 1e-4;
      const double fdx = (u(x + h, y) - u(x - h, y)) / (2 * h);
      const double fdy = (u(x, y + h) - u(x, y - h)) / (2 * h);
      const double lap = (u(x + h, y) + u(x - h, y) + u(x, y + h) + u(x, y - h) - 4 * u(x, y)) / (h * h);
      REQUIRE(std::abs(ux(x, y) - fdx) < 1e-7 * (1 + std::abs(fdx)));
      REQUIRE(std::abs(uy(x, y) - fdy) < 1e-7 * (1 + std::abs(fdy)));
      REQUIRE(std::abs(f(x, y) + lap) < 1e-4 * (1 + std::abs(lap)));
    }
  }
}

TEST_CASE("Surface solutions: ambient gradient and Hessian in x, y, z", "[expression][surface]") {
  const ExactSolution s = differentiate_surface_solution(Expression::parse("x*y*z + sin(z)", "f"));
  ExpressionEvaluator gz(s.u_z), hzz(s.hessian[2][2]), hxy(s.hessian[0][1]), hyz(s.hessian[1][2]);
  const double x = 0.3, y = -0.7, z = 0.45;
  REQUIRE(gz(x, y, z) == Approx(x * y + std::cos(z)));
  REQUIRE(hzz(x, y, z) == Approx(-std::sin(z)));
  REQUIRE(hxy(x, y, z) == Approx(z));
  REQUIRE(hyz(x, y, z) == Approx(x));
}

TEST_CASE("A batch of expressions gives each one's own values, sharing what they have in common", "[expression]") {
  // The reference is each expression alone at one point, and for the user's texts the same
  // formula written in C++ here.
  const ExactSolution ex = differentiate_exact_solution(
      Expression::parse("(x^2+y^2)^(1/3)*sin(2/3*(atan2(-y,-x)+pi)) + exp(-x^2)*cos(y-0.3)", "t"));
  std::vector<Expression> texts{ex.u, ex.u_x, ex.u_y, ex.minus_laplacian};
  const std::vector<std::pair<const char*, double (*)(double, double, double)>> formulas{
      {"sin(pi*x)*sin(pi*y)", [](double x, double y, double) { return std::sin(M_PI * x) * std::sin(M_PI * y); }},
      {"x^-3 + y^7 - 2^x + e^y",
       [](double x, double y, double) { return 1 / (x * x * x) + std::pow(y, 7) - std::pow(2, x) + std::exp(y); }},
      {"sqrt(1+x^2)*cosh(y)/(2+tan(x*y))",
       [](double x, double y, double) { return std::sqrt(1 + x * x) * std::cosh(y) / (2 + std::tan(x * y)); }},
      {"log(x^2+1) + asin(y/3) + acos(x/4) + atan(x) + sinh(y) + tanh(x) + pow(x, 2.5)",
       [](double x, double y, double) {
         return std::log(x * x + 1) + std::asin(y / 3) + std::acos(x / 4) + std::atan(x) + std::sinh(y) + std::tanh(x) +
                std::pow(x, 2.5);
       }},
      {"x*y*z + 3 + abs(y - 0.3)", [](double x, double y, double z) { return x * y * z + 3 + std::abs(y - 0.3); }}};
  for (const auto& f : formulas) texts.push_back(Expression::parse(f.first, "t"));
  const ExpressionBatch compiled(texts);
  ExpressionBatch batch(compiled);  // what every thread does: its own copy
  std::vector<double> x, y, z;
  for (int i = 0; i < 40; ++i) {
    x.push_back(0.05 + 0.9 * std::fmod(0.37 * i, 1.0));
    y.push_back(-0.8 + 1.7 * std::fmod(0.61 * i + 0.2, 1.0));
    z.push_back(0.3 * i - 4);
  }
  batch.evaluate(x.data(), y.data(), z.data(), static_cast<long>(x.size()));
  for (size_t e = 0; e < texts.size(); ++e) {
    ExpressionEvaluator alone(texts[e]);
    for (size_t k = 0; k < x.size(); ++k) {
      INFO(texts[e].text() << " at (" << x[k] << ", " << y[k] << ", " << z[k] << ")");
      const double r = alone(x[k], y[k], z[k]), b = batch.result(static_cast<int>(e))[k];
      REQUIRE(std::isfinite(r));
      REQUIRE(b == r);  // the same instructions in the same order
      if (e >= 4) {
        // A few roundings apart from the C++ formula: each operation rounds once, in both.
        const double formula = formulas[e - 4].second(x[k], y[k], z[k]);
        REQUIRE(std::abs(b - formula) <= 64 * 2.2e-16 * (1 + std::abs(formula)));
      }
    }
  }
  // Without z the batch sets z = 0, as the scalar evaluator does in the plane.
  batch.evaluate(x.data(), y.data(), nullptr, 5);
  ExpressionEvaluator xyz(texts.back());
  REQUIRE(batch.result(static_cast<int>(texts.size()) - 1)[3] == xyz(x[3], y[3]));
}

TEST_CASE("The derivatives are those of the function evaluated: one reading of the text", "[expression]") {
  // GiNaC's own parser reads (x+2)^-1*2 as (x+2)^(-2); the grammar, like the evaluator, as
  // 2/(x+2). Derived from the same tree, u_x = -2/(x+2)^2 and -Laplacian = -4/(x+2)^3.
  const ExactSolution u = differentiate_exact_solution(Expression::parse("(x+2)^-1*2", "c: [problem] exact"));
  ExpressionEvaluator value(u.u), ux(u.u_x), f(u.minus_laplacian);
  REQUIRE(value(0.5, 0.3) == Approx(2.0 / 2.5).epsilon(1e-15));
  REQUIRE(ux(0.5, 0.3) == Approx(-2.0 / (2.5 * 2.5)).epsilon(1e-14));
  REQUIRE(f(0.5, 0.3) == Approx(-4.0 / (2.5 * 2.5 * 2.5)).epsilon(1e-14));
  // Found by fuzzing (nested powers whose exact value at a check point asked CLN for 4.8 TB
  // under GiNaC's reading): under the grammar's reading, the exponents are x^(-3*y^2*...), no
  // constant power is large, and the derivatives come in a fraction of a second.
  REQUIRE_NOTHROW(differentiate_exact_solution(
      Expression::parse("x*(x^ - 3*y^2*(3^ 2*(x^ - 3*y^2*(x^ -y*6^ 2))))", "c: [problem] exact")));
}

TEST_CASE("Exact solutions double precision cannot carry are refused with the field, not crashed on", "[expression]") {
  // Found by fuzzing: a constant beyond 2^53 makes the printed derivative differ from GiNaC's
  // exact value (an internal logic_error before); an exponent whose exact power underflows
  // made CLN throw its own exception out of the check (now such exponents are refused first).
  REQUIRE_THROWS_WITH(differentiate_exact_solution(Expression::parse("sin(2333333333333333333333/3*x)", "c: [problem] exact")),
                      Catch::StartsWith("c: [problem] exact: ") && Catch::Contains("double precision"));
  REQUIRE_THROWS_WITH(differentiate_surface_solution(
                          Expression::parse("sqrt(x^21111111111111111111111111111111 + y^2)*z", "c: [problem] exact")),
                      Catch::StartsWith("c: [problem] exact: ") && Catch::Contains("exponent beyond 10000"));
}

TEST_CASE("A power of numbers too large for exact arithmetic is refused, not computed for hours", "[expression]") {
  // Found by fuzzing: GiNaC computes 4777^775777777 (2.8 billion digits) exactly while parsing.
  REQUIRE_THROWS_WITH(differentiate_exact_solution(Expression::parse("x*4777^775777777", "c: [problem] exact")),
                      Catch::StartsWith("c: [problem] exact: ") && Catch::Contains("exponent beyond 10000"));
  REQUIRE_THROWS_WITH(differentiate_exact_solution(Expression::parse("2^(7757*77777) + y", "c: [problem] exact")),
                      Catch::Contains("exponent beyond 10000"));
  REQUIRE_THROWS_WITH(differentiate_exact_solution(Expression::parse("x*(x^ - 3444444444444444444*y^2)", "c: [problem] exact")),
                      Catch::Contains("exponent beyond 10000"));
  // Small exponents whose nesting or value is beyond what exact arithmetic can afford: (7^9999)^9999
  // has 84 million digits (it took 5 s and 0.6 GB; one more level exhausted the memory).
  REQUIRE_THROWS_WITH(differentiate_exact_solution(Expression::parse("(7^9999)^9999*x", "c: [problem] exact")),
                      Catch::Contains("constant power beyond double precision (7^9999)"));
  REQUIRE_THROWS_WITH(differentiate_exact_solution(Expression::parse("((9999/9998)^9999)^9999*x", "c: [problem] exact")),
                      Catch::Contains("nested constant exponents with a product beyond 10000"));
  REQUIRE_THROWS_WITH(differentiate_exact_solution(Expression::parse("x + 7^-(9999*9999)", "c: [problem] exact")),
                      Catch::Contains("exponent beyond 10000"));
  // Exponents that are not constant, or not large, stay exact.
  REQUIRE_NOTHROW(differentiate_exact_solution(Expression::parse("x^y + 3^40*y + exp(-x^2)", "c: [problem] exact")));
  // The program evaluates such a text in double, as written: inf * 0.
  ExpressionBatch batch({Expression::parse("4777^775777777 * 0 + x", "t")});
  const double x[1] = {0.25}, y[1] = {0.5};
  batch.evaluate(x, y, nullptr, 1);
  REQUIRE(std::isnan(batch.result(0)[0]));
}

TEST_CASE("Powers GiNaC cannot evaluate are refused before GiNaC sees them", "[expression]") {
  // Found by fuzzing: 9^0^0 is 9^(0^0); GiNaC threw on 0^0 and lost the power it had allocated.
  for (const char* text : {"9^0^0 + x", "x/(2-2)", "x*0^(-1)", "pow(0, -2)*y"}) {
    INFO(text);
    REQUIRE_THROWS_WITH(differentiate_exact_solution(Expression::parse(text, "c: [problem] exact")),
                        Catch::StartsWith("c: [problem] exact: cannot differentiate") &&
                            (Catch::Contains("undefined") || Catch::Contains("division by zero")));
  }
}


// solver/vector_math: glibc's libmvec over arrays. Against the scalar functions within glibc's
// bound of 4 ulp (finite results), the same special values (NaN, infinities, zeros), and a value
// that does not depend on where it sits in the array or on the array's length (the padded tail).
namespace {
long ulps_apart(double a, double b) {
  if (a == b) return 0;
  std::int64_t x, y;
  std::memcpy(&x, &a, 8);
  std::memcpy(&y, &b, 8);
  if ((x < 0) != (y < 0)) return std::numeric_limits<long>::max();
  return static_cast<long>(x > y ? x - y : y - x);
}
bool same_special(double a, double b) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  if (std::isinf(a) || std::isinf(b)) return a == b;
  return true;
}
}  // namespace

TEST_CASE("Array functions from libmvec: scalar values within 4 ulp, special values, any position", "[expression]") {
  INFO("lanes: " << vector_math_kind());
  std::vector<double> a;
  for (int k = 0; k < 2000; ++k) a.push_back(-60 + 0.0617 * k);
  for (double v : {0.0, -0.0, 1e-300, -1e-300, 1e-8, 1.0, 2.0, 700.0, 710.0, -746.0, 1e5, 1e22, -1e22,
                   std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                   std::numeric_limits<double>::quiet_NaN()})
    a.push_back(v);
  const std::vector<std::pair<const char*, double (*)(double)>> unary{
      {"sin", [](double x) { return std::sin(x); }}, {"cos", [](double x) { return std::cos(x); }},
      {"exp", [](double x) { return std::exp(x); }}, {"log", [](double x) { return std::log(x); }},
      {"tan", [](double x) { return std::tan(x); }}, {"asin", [](double x) { return std::asin(x); }},
      {"acos", [](double x) { return std::acos(x); }}, {"atan", [](double x) { return std::atan(x); }},
      {"sinh", [](double x) { return std::sinh(x); }}, {"cosh", [](double x) { return std::cosh(x); }},
      {"tanh", [](double x) { return std::tanh(x); }}};
  // asin and acos live on [-1, 1]: a second copy of the points scaled into it (and the rest,
  // outside, must give NaN as the scalar functions do).
  for (long k = 0; k < 2000; k += 3) a.push_back(a[k] / 60);
  const long n = static_cast<long>(a.size());
  std::vector<double> t(n), b(n, 0.5), alone(1);
  for (long k = 0; k < n; ++k) b[k] = k % 7 == 0 ? -2.0 : 0.25 * (k % 9) - 0.5;
  for (const auto& [name, scalar] : unary) {
    const ArrayFunction1 f = array_function(name);
    REQUIRE(f);
    f(a.data(), t.data(), n);
    for (long k = 0; k < n; ++k) {
      INFO(name << "(" << a[k] << ") = " << t[k] << ", scalar " << scalar(a[k]));
      REQUIRE(same_special(t[k], scalar(a[k])));
      if (std::isfinite(scalar(a[k]))) REQUIRE(ulps_apart(t[k], scalar(a[k])) <= 4);
      // Alone, and at every length up to 9 from here: the same bits.
      f(&a[k], alone.data(), 1);
      REQUIRE(std::memcmp(&alone[0], &t[k], 8) == 0);
    }
    for (long length = 1; length <= 9; ++length)
      for (long first = 0; first + length <= 40; first += 3) {
        std::vector<double> part(length);
        f(&a[first], part.data(), length);
        REQUIRE(std::memcmp(part.data(), &t[first], 8 * length) == 0);
      }
  }
  // Two arguments: each value against the scalar function, and alone the same bits.
  const auto check_two = [&](const char* name, ArrayFunction2 f, double (*scalar)(double, double),
                             const std::vector<double>& x, const std::vector<double>& y) {
    REQUIRE(f);
    f(x.data(), y.data(), t.data(), n);
    for (long k = 0; k < n; ++k) {
      const double expected = scalar(x[k], y[k]);
      INFO(name << "(" << x[k] << ", " << y[k] << ") = " << t[k] << ", scalar " << expected);
      REQUIRE(same_special(t[k], expected));
      if (std::isfinite(expected)) REQUIRE(ulps_apart(t[k], expected) <= 4);
      f(&x[k], &y[k], alone.data(), 1);
      REQUIRE(std::memcmp(&alone[0], &t[k], 8) == 0);
    }
  };
  std::vector<double> base(n);
  for (long k = 0; k < n; ++k) base[k] = std::abs(a[k]) < 50 ? a[k] : 1.5;
  check_two("pow", array_pow(), [](double x, double y) { return std::pow(x, y); }, base, b);
  // atan2(y, x) in every quadrant, on the axes (signed zeros) and at infinities.
  std::vector<double> across(n);
  for (long k = 0; k < n; ++k) across[k] = k % 5 == 0 ? -0.0 : k % 5 == 1 ? 0.0 : k % 5 == 2 ? a[(k * 7) % n] : b[k] * 3;
  check_two("atan2", array_atan2(), [](double x, double y) { return std::atan2(x, y); }, a, across);
  REQUIRE(array_function("sqrt") == nullptr);  // exact in every lane already: stays scalar
}
