// knotwork._core: the studies of studies/studies.hpp for Python, through pybind11. The public
// API and its documentation are in knotwork/__init__.py; this file converts cases (paths or
// dicts) in, and the studies' JSON objects, solutions and spaces out.
// - Results are the CLI's own JSON objects (run_json, ...), so Python and `--json` agree
//   bit for bit; arrays (coefficients, extraction matrices) are numpy views of the C++
//   data, kept alive by the object that owns them.
// - Every long call releases the GIL; the progress hook reacquires it to call the user's
//   callback and to let Ctrl-C (KeyboardInterrupt) stop the study between its phases.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "studies/studies.hpp"
#include "studies/system_study.hpp"
#include "basis/core/bezier_mesh_checks.hpp"
#include "solver/blas_kernel.hpp"
#include "solver/error_norms.hpp"
#include "solver/cell_basis.hpp"
#include "solver/expression.hpp"
#include "solver/point_location.hpp"
#include "basis/core/input_error.hpp"

namespace py = pybind11;

extern "C" void openblas_set_num_threads(int);

namespace knotwork {
namespace {

// ---- problems given as Python functions ----

// The first error a case's Python functions raised while C++ evaluated them (in any thread): the
// function returns NaN there, and the error is raised again when the study returns.
struct PythonErrors {
  std::mutex mutex;
  std::optional<py::error_already_set> first;
  void record(py::error_already_set&& e) {
    std::lock_guard<std::mutex> lock(mutex);
    if (!first) first.emplace(std::move(e));
  }
  // Raises the recorded error, if any (with the GIL held).
  void raise() {
    std::optional<py::error_already_set> e;
    {
      std::lock_guard<std::mutex> lock(mutex);
      e.swap(first);
    }
    if (e) throw std::move(*e);
  }
};
using SharedErrors = std::shared_ptr<PythonErrors>;

// A vectorized numpy function f(x, y) (or f(x, y, z), by its signature) as an ExternalFunction:
// called once per batch of points (a cell's quadrature points) with the GIL taken; it returns n
// values, or one for all. The Python object is released with the GIL held, whichever thread
// drops the last copy.
ExternalFunction python_function(py::object f, const std::string& where, SharedErrors errors) {
  const int arity = [&] {
    try {
      py::object signature = py::module_::import("inspect").attr("signature")(f);
      int positional = 0;
      for (py::handle p : signature.attr("parameters").attr("values")()) {
        const std::string kind = py::str(p.attr("kind").attr("name"));
        if (kind == "VAR_POSITIONAL") return 3;
        if (kind == "POSITIONAL_ONLY" || kind == "POSITIONAL_OR_KEYWORD") ++positional;
      }
      return positional >= 3 ? 3 : 2;
    } catch (py::error_already_set&) {
      return 2;  // a builtin or ufunc without a signature: f(x, y)
    }
  }();
  std::shared_ptr<py::object> held(new py::object(std::move(f)), [](py::object* o) {
    py::gil_scoped_acquire gil;
    delete o;
  });
  return [held, arity, where, errors](const double* x, const double* y, const double* z, long n, double* out) {
    py::gil_scoped_acquire gil;
    try {
      py::array_t<double> X(n, x), Y(n, y), Z(n);
      std::fill(Z.mutable_data(), Z.mutable_data() + n, 0.0);
      if (z) std::copy(z, z + n, Z.mutable_data());
      py::object r = arity == 3 ? (*held)(X, Y, Z) : (*held)(X, Y);
      py::array_t<double> a = py::array_t<double, py::array::forcecast>::ensure(r);
      if (!a) throw std::invalid_argument(where + ": the Python function returned " + py::repr(r).cast<std::string>() + ", not numbers");
      if (a.ndim() == 0 || (a.ndim() == 1 && a.shape(0) == 1)) std::fill(out, out + n, a.data()[0]);
      else if (a.ndim() == 1 && a.shape(0) == n) std::copy(a.data(), a.data() + n, out);
      else
        throw std::invalid_argument(where + ": the Python function must return n values (or one) for n points; for " +
                                    std::to_string(n) + " it returned shape " +
                                    py::str(py::tuple(py::cast(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim())))).cast<std::string>());
    } catch (py::error_already_set& e) {
      errors->record(std::move(e));
      std::fill(out, out + n, std::numeric_limits<double>::quiet_NaN());
    } catch (const std::exception& e) {  // a result of the wrong kind (nothing may leave an OpenMP region)
      PyErr_SetString(PyExc_ValueError, e.what());
      errors->record(py::error_already_set());
      std::fill(out, out + n, std::numeric_limits<double>::quiet_NaN());
    }
  };
}

bool is_python_function(py::handle v) {
  return PyCallable_Check(v.ptr()) && !py::isinstance<py::type>(v);
}

// ---- dict cases: the same document tree a TOML or JSON file becomes ----

constexpr int kMaxDepth = 200;  // as for JSON files

std::string member_name(const std::string& where, const std::string& key, int depth) {
  if (depth == 0) return key;
  if (depth == 1) return "[" + where + "] " + key;
  return where + "." + key;
}

[[noreturn]] void refuse(const std::string& name, const std::string& where, const std::string& what) {
  throw InputError(name + ": " + (where.empty() ? std::string("case") : where) + ": " + what);
}

// Where a dict case's Python functions go: each becomes a placeholder name in the document,
// which Expression::parse reads as the function while `names` is alive.
struct DictFunctions {
  ExternalFunctionNames* names = nullptr;
  SharedErrors errors;
};

DocumentNode to_document(py::handle v, const std::string& name, const std::string& where, int depth,
                         DictFunctions* functions = nullptr) {
  if (depth > kMaxDepth) refuse(name, where, "nested deeper than " + std::to_string(kMaxDepth) + " levels");
  if (v.is_none()) refuse(name, where, "None is not a value (leave the key out for the default)");
  if (functions && is_python_function(v))
    return DocumentNode::string(functions->names->add(std::make_shared<const ExternalFunction>(
        python_function(py::reinterpret_borrow<py::object>(v), name + ": " + where, functions->errors))));
  if (py::isinstance<py::bool_>(v)) return DocumentNode::boolean(v.cast<bool>());
  if (py::isinstance<py::float_>(v)) return DocumentNode::floating(v.cast<double>());
  if (PyIndex_Check(v.ptr())) {  // Python and numpy integers
    int overflow = 0;
    py::object index = py::reinterpret_steal<py::object>(PyNumber_Index(v.ptr()));
    if (!index) throw py::error_already_set();
    const long long x = PyLong_AsLongLongAndOverflow(index.ptr(), &overflow);
    if (overflow) refuse(name, where, "integer out of the 64-bit range");
    return DocumentNode::integer(x);
  }
  if (py::isinstance<py::str>(v)) return DocumentNode::string(v.cast<std::string>());
  if (py::isinstance<py::dict>(v)) {
    DocumentNode t = DocumentNode::table();
    for (auto item : v.cast<py::dict>()) {
      if (!py::isinstance<py::str>(item.first))
        refuse(name, where, "key " + py::repr(item.first).cast<std::string>() + " is not a string");
      const std::string key = item.first.cast<std::string>();
      t.insert(key, to_document(item.second, name, member_name(where, key, depth), depth + 1, functions));
    }
    return t;
  }
  if (py::hasattr(v, "tolist") && py::hasattr(v, "ndim"))  // numpy arrays and scalars
    return to_document(v.attr("tolist")(), name, where, depth, functions);
  if (py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v)) {
    DocumentNode a = DocumentNode::array();
    size_t i = 0;
    for (auto item : v) {
      a.push_back(to_document(item, name, where + "[" + std::to_string(i) + "]", depth + 1, functions));
      ++i;
    }
    return a;
  }
  refuse(name, where,
         "a value of type " + py::str(py::type::of(v).attr("__name__")).cast<std::string>() +
             " is not a case-file value (use numbers, strings, booleans, lists and dicts)");
}

// A case and where its Python functions' errors go (null for a file).
struct LoadedCase {
  CaseDescription c;
  SharedErrors errors;
};

// A dict case whose [problem] exact is a Python function: that function and its gradient
// (exact_gradient: 2 functions in the plane, 3 on surfaces) are taken out of the dict (the
// readers differentiate `exact`) and become the case's exact solution once it is read; the
// source, which cannot be derived from them, must be given.
LoadedCase load_dict_case(py::dict d, const std::string& name) {
  LoadedCase loaded{CaseDescription(), std::make_shared<PythonErrors>()};
  py::object exact, gradient;
  if (d.contains("problem") && py::isinstance<py::dict>(d["problem"])) {
    // Copies (py::dict(x) of a dict is the same dict): the caller's dicts are left as they were.
    py::dict problem = py::reinterpret_steal<py::dict>(PyDict_Copy(py::object(d["problem"]).ptr()));
    if (problem.contains("exact") && is_python_function(problem["exact"])) {
      exact = problem["exact"];
      PyDict_DelItemString(problem.ptr(), "exact");
      if (!problem.contains("exact_gradient"))
        refuse(name, "[problem] exact_gradient",
               "missing: a Python exact solution needs its gradient, as Python functions (u_x, u_y), or (u_x, u_y, u_z) "
               "on a surface (the error norms and flux data use it)");
      gradient = problem["exact_gradient"];
      PyDict_DelItemString(problem.ptr(), "exact_gradient");
      const bool sequence = py::isinstance<py::list>(gradient) || py::isinstance<py::tuple>(gradient);
      const size_t n = sequence ? py::len(gradient) : 0;
      bool callables = sequence && (n == 2 || n == 3);
      if (callables)
        for (py::handle g : gradient) callables = callables && is_python_function(g);
      if (!callables)
        refuse(name, "[problem] exact_gradient",
               "give 2 Python functions (u_x, u_y), or 3 (u_x, u_y, u_z) on a surface, not " +
                   py::repr(gradient).cast<std::string>());
      if (!problem.contains("source"))
        refuse(name, "[problem] source",
               "missing: it cannot be derived from a Python exact solution (give it as a formula or a Python function)");
    } else if (problem.contains("exact_gradient")) {
      refuse(name, "[problem] exact_gradient", "only with a Python function as exact (a formula's gradient is derived)");
    }
    // The readers see exact = "0" (its derivatives are harmless to compute; data that come
    // "from the exact solution" are then accepted) and the functions replace it below.
    if (exact) problem["exact"] = "0";
    d = py::reinterpret_steal<py::dict>(PyDict_Copy(d.ptr()));
    d["problem"] = problem;
  }
  ExternalFunctionNames names;
  DictFunctions functions{&names, loaded.errors};
  loaded.c = load_case_document(to_document(d, name, "", 0, &functions), name);
  if (exact) {
    const auto external = [&](py::handle f, const std::string& field) {
      const std::string where = name + ": [problem] " + field;
      return Expression::external(
          std::make_shared<const ExternalFunction>(
              python_function(py::reinterpret_borrow<py::object>(f), where, loaded.errors)),
          "Python function " + py::str(py::getattr(f, "__name__", py::str("?"))).cast<std::string>(), where);
    };
    ExactSolution u;
    u.u = external(exact, "exact");
    std::vector<py::handle> g(gradient.begin(), gradient.end());
    u.u_x = external(g[0], "exact_gradient[0]");
    u.u_y = external(g[1], "exact_gradient[1]");
    if (g.size() == 3) u.u_z = external(g[2], "exact_gradient[2]");
    loaded.c.problem.exact = std::move(u);
  }
  return loaded;
}

// A case given as a path (str or os.PathLike) or as a dict in the case-file schema.
LoadedCase load_any_case(py::handle c, const std::string& name) {
  if (py::isinstance<py::dict>(c)) return load_dict_case(py::reinterpret_borrow<py::dict>(c), name);
  if (py::isinstance<py::str>(c) || py::hasattr(c, "__fspath__"))
    return {load_case(py::module_::import("os").attr("fspath")(c).cast<std::string>()), nullptr};
  throw InputError("case: give a case-file path or a dict in the case-file schema, not a " +
                   py::str(py::type::of(c).attr("__name__")).cast<std::string>());
}

// ---- progress, Ctrl-C, and the GIL ----

// Thrown through the C++ study when the callback raised or Ctrl-C was pressed. Not a
// std::exception, so that no handler on the way turns it into an InputError.
struct PythonRaised {};

class PythonHooks {
 public:
  explicit PythonHooks(py::object callback, SharedErrors errors = nullptr)
      : callback_(std::move(callback)), errors_(std::move(errors)) {}
  // Called with the GIL released; takes it for the callback and the signal check.
  ProgressFunction progress() {
    return [this](const std::string& what) {
      py::gil_scoped_acquire gil;
      try {
        if (PyErr_CheckSignals() != 0) throw py::error_already_set();
        if (!callback_.is_none()) callback_(what);
      } catch (py::error_already_set& e) {
        error_.emplace(std::move(e));
        throw PythonRaised{};
      }
    };
  }
  // Runs f(progress) without the GIL; a Python error raised inside is raised again here.
  // An error raised by one of the case's Python functions comes first: the study's own error
  // (a source that is not finite) is its consequence.
  template <class F>
  auto call(F&& f) {
    try {
      auto result = [&] {
        py::gil_scoped_release nogil;
        return f(progress());
      }();
      if (errors_) errors_->raise();
      return result;
    } catch (const PythonRaised&) {
      py::error_already_set e = std::move(*error_);
      error_.reset();
      throw e;
    } catch (const InputError&) {
      if (errors_) errors_->raise();
      throw;
    }
  }

 private:
  py::object callback_;
  SharedErrors errors_;
  std::optional<py::error_already_set> error_;
};

// ---- overrides of the case, the same as the command line's options ----

struct Overrides {
  int degree = 0, elements = 0;
  std::string solver, ordering = "auto", preconditioner, matrix;
  double tolerance = 0;
  bool allow_unverified_space = false;
  std::string marking;  // adapt: "" (the case's), "cells" or "functions"
  std::string strategy;  // adapt: "" (the case's), "dorfler" or "maximum"
  double min_fraction = -1;  // adapt: < 0 (the case's), or in [0, 1]
};

Overrides read_overrides(const py::dict& d) {
  Overrides o;
  for (auto item : d) {
    const std::string key = item.first.cast<std::string>();
    py::handle v = item.second;
    if (v.is_none()) continue;
    auto positive_int = [&](int& out) {
      if (py::isinstance<py::bool_>(v) || !PyIndex_Check(v.ptr()))
        throw InputError(key + ": must be an integer, got " + py::repr(v).cast<std::string>());
      const long long x = py::int_(py::reinterpret_borrow<py::object>(v)).cast<long long>();
      if (x < 1 || x > std::numeric_limits<int>::max()) throw InputError(key + ": must be >= 1, got " + std::to_string(x));
      out = static_cast<int>(x);
    };
    auto number = [&](double& out) {
      if (py::isinstance<py::bool_>(v) || !(py::isinstance<py::float_>(v) || PyIndex_Check(v.ptr())))
        throw InputError(key + ": must be a number, got " + py::repr(v).cast<std::string>());
      out = py::float_(py::reinterpret_borrow<py::object>(v)).cast<double>();
    };
    auto text = [&](std::string& out) {
      if (!py::isinstance<py::str>(v)) throw InputError(key + ": must be a string, got " + py::repr(v).cast<std::string>());
      out = v.cast<std::string>();
    };
    if (key == "degree") positive_int(o.degree);
    else if (key == "elements") positive_int(o.elements);
    else if (key == "solver") text(o.solver);
    else if (key == "ordering") text(o.ordering);
    else if (key == "preconditioner") text(o.preconditioner);
    else if (key == "matrix") text(o.matrix);
    else if (key == "tolerance") {
      number(o.tolerance);
      // The range is checked by override_solver, as for --tolerance; 0 means "not given" there.
      if (o.tolerance == 0) throw InputError("tolerance: must be in (0, 1), got 0");
    } else if (key == "allow_unverified_space") o.allow_unverified_space = py::bool_(py::reinterpret_borrow<py::object>(v)).cast<bool>();
    else if (key == "marking") {
      text(o.marking);
      if (o.marking != "cells" && o.marking != "functions")
        throw InputError("marking: must be \"cells\" or \"functions\", got \"" + o.marking + "\"");
    } else if (key == "strategy") {
      text(o.strategy);
      if (o.strategy != "dorfler" && o.strategy != "maximum")
        throw InputError("strategy: must be \"dorfler\" or \"maximum\", got \"" + o.strategy + "\"");
    } else if (key == "min_fraction") {
      number(o.min_fraction);
      if (!(o.min_fraction >= 0 && o.min_fraction <= 1))
        throw InputError("min_fraction: must be in [0, 1], got " + py::repr(v).cast<std::string>());
    }
    else throw std::logic_error("unknown override " + key);  // knotwork/__init__.py passes only these
  }
  return o;
}

CaseDescription prepared_case(py::handle case_, const std::string& name, const py::dict& overrides, Ordering* ordering,
                              SharedErrors* errors = nullptr) {
  LoadedCase loaded = load_any_case(case_, name);
  if (errors) *errors = loaded.errors;
  CaseDescription c = std::move(loaded.c);
  const Overrides o = read_overrides(overrides);
  override_case(c, o.degree, o.elements, o.solver, o.tolerance, nullptr, o.preconditioner, o.matrix);
  c.allow_unverified_space = o.allow_unverified_space;
  if (!o.marking.empty()) c.adapt.mark_functions = o.marking == "functions";
  if (!o.strategy.empty()) c.adapt.maximum_strategy = o.strategy == "maximum";
  if (o.min_fraction >= 0) c.adapt.min_fraction = o.min_fraction;
  if (ordering) *ordering = parse_ordering(o.ordering);
  c.solver.ordering = o.ordering;
  return c;
}

std::optional<std::string> output_of(const py::object& output) {
  if (output.is_none()) return std::nullopt;
  return py::module_::import("os").attr("fspath")(output).cast<std::string>();
}

// ---- numpy views ----

template <class T>
py::array view(const T* data, std::vector<py::ssize_t> shape, std::vector<py::ssize_t> strides, py::handle owner) {
  py::array a(py::dtype::of<T>(), std::move(shape), std::move(strides), data, owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

// ---- the space ----

// The case is shared, never moved: a family's space may keep a reference to its case.
using SharedCase = std::shared_ptr<const CaseDescription>;

struct Space {
  SharedCase case_;
  std::shared_ptr<const SplineSpace> space;
  const CaseDescription& c() const { return *case_; }
  const BezierMesh& mesh() const { return space->mesh(); }
  int checked_cell(long cell) const {
    if (cell < 0 || cell >= mesh().num_cells())
      throw py::index_error("cell " + std::to_string(cell) + " out of range (the space has " +
                            std::to_string(mesh().num_cells()) + " cells)");
    return static_cast<int>(cell);
  }
};

// Solution, exact solution and gradient on an (n+1) x (n+1) grid of each cell's reference
// square, in physical space: arrays [cell, j, i] with i along u, j along v; on a volume's
// hexahedra the (n+1)^3 grid of each cell's cube, [cell, k, j, i] with k along w.
py::dict sample(const CaseDescription& c, const SplineSpace& space, const PoissonSolution& s, int n) {
  const BezierMesh& mesh = space.mesh();
  const GeometryMap& geometry = space.geometry();
  if (n < 1 || n > 256) throw InputError("sample: n must be in [1, 256], got " + std::to_string(n));
  const bool volume = geometry.parametric_dimension() == 3;
  const py::ssize_t cells = mesh.num_cells(), m = n + 1, dim = geometry.dimension(), per_cell = volume ? m * m * m : m * m;
  if (double(cells) * per_cell * (2 * dim + 3) > 2.5e8)
    throw InputError("sample: " + std::to_string(cells) + " cells x " + std::to_string(per_cell) +
                     " points would need more than 2 GB; use a smaller n");
  std::vector<py::ssize_t> grid{cells};
  for (int d = 0; d < (volume ? 3 : 2); ++d) grid.push_back(m);
  std::vector<py::ssize_t> vectors = grid;
  vectors.push_back(dim);
  py::array_t<double> points(vectors), values(grid), gradient(vectors);
  std::optional<py::array_t<double>> exact;
  if (c.problem.exact) exact.emplace(grid);
  double *px = points.mutable_data(), *pu = values.mutable_data(), *pg = gradient.mutable_data();
  double* pe = exact ? exact->mutable_data() : nullptr;
  {
    py::gil_scoped_release nogil;
    std::optional<ExpressionEvaluator> ev;
    if (c.problem.exact) ev.emplace(c.problem.exact->u);
    CellSamples cs;
    for (int cell = 0; cell < cells; ++cell) {
      sample_cell(mesh, geometry, s.coefficients, cell, n, ev ? &*ev : nullptr, s.exact_mean, cs);
      for (py::ssize_t k = 0; k < per_cell; ++k) {
        const py::ssize_t at_k = cell * per_cell + k;
        pu[at_k] = cs.uh(k, 0);
        for (int d = 0; d < dim; ++d) px[at_k * dim + d] = cs.at.x(k, d), pg[at_k * dim + d] = cs.uh(k, 1 + d);
        if (pe) pe[at_k] = cs.exact[k];
      }
    }
  }
  py::dict r;
  r["points"] = points;
  r["solution"] = values;
  r["gradient"] = gradient;
  if (exact) {
    r["exact"] = *exact;
    r["error"] = py::array_t<double>(values.attr("__sub__")(*exact));
  } else {
    r["exact"] = py::none();
    r["error"] = py::none();
  }
  if (volume) {  // no triangles for a plot: the sampled .vtu shows a volume
    r["triangles"] = py::none();
    return r;
  }
  // Two triangles per little square, indices into the flattened points (for tripcolor).
  py::array_t<long> triangles({cells * n * n * 2, py::ssize_t(3)});
  long* t = triangles.mutable_data();
  for (py::ssize_t cell = 0; cell < cells; ++cell)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const long a = cell * m * m + i + m * j, b = a + 1, d = a + m, e = d + 1;
        *t++ = a, *t++ = b, *t++ = e;
        *t++ = a, *t++ = e, *t++ = d;
      }
  r["triangles"] = triangles;
  return r;
}

// ---- one solve ----

struct Run {
  SharedCase case_;
  std::shared_ptr<RunOutcome> outcome;
  SharedErrors errors;                          // of the case's Python functions (sample() evaluates exact)
  std::shared_ptr<const PointLocator> locator;  // built by the first evaluate()
  const CaseDescription& c() const { return *case_; }
};

// Points as an n x dimension float64 array (a single point may be given flat).
py::array_t<double, py::array::c_style> point_array(py::handle points, int dim, const char* what) {
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(points);
  if (!a) throw InputError(std::string(what) + ": points must be an array of numbers");
  if (a.ndim() == 1 && a.shape(0) == dim) a = a.reshape({py::ssize_t(1), py::ssize_t(dim)});
  if (a.ndim() != 2 || a.shape(1) != dim)
    throw InputError(std::string(what) + ": points must have shape (n, " + std::to_string(dim) + "), got " +
                     py::str(py::tuple(py::cast(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim())))).cast<std::string>());
  return a;
}

// u_h and its gradient at physical points; points outside the domain (or farther than
// `distance` from a surface) are refused together, by index.
py::dict evaluate_solution(Run& r, py::handle points, py::object distance) {
  const SplineSpace& space = *r.outcome->space;
  const int dim = space.geometry().dimension();
  const auto p = point_array(points, dim, "evaluate");
  const py::ssize_t n = p.shape(0);
  double max_distance = 0;
  // Built with the GIL held: two Python threads evaluating one result must not both build it.
  if (!r.locator) r.locator = std::make_shared<const PointLocator>(space.mesh(), space.geometry());
  if (dim == 3) max_distance = distance.is_none() ? 1e-8 * r.locator->diameter() : distance.cast<double>();
  if (!(max_distance >= 0)) throw InputError("evaluate: distance must be >= 0");
  std::vector<LocatedPoint> located(n);
  Eigen::VectorXd value;
  Eigen::MatrixXd gradient;
  std::vector<py::ssize_t> outside;
  {
    py::gil_scoped_release nogil;
    const double* data = p.data();
    for (py::ssize_t k = 0; k < n; ++k) {
      bool finite = true;
      for (int d = 0; d < dim; ++d) finite = finite && std::isfinite(data[k * dim + d]);
      if (finite) located[k] = r.locator->locate(data + k * dim, max_distance);
      if (located[k].cell < 0) outside.push_back(k);
    }
    if (outside.empty()) evaluate_at_points(space.mesh(), space.geometry(), r.outcome->solution.coefficients, located,
                                            value, gradient);
  }
  if (!outside.empty()) {
    std::string list;
    for (size_t k = 0; k < outside.size() && k < 10; ++k) list += (k ? ", " : "") + std::to_string(outside[k]);
    if (outside.size() > 10) list += ", ...";
    throw InputError("evaluate: " + std::to_string(outside.size()) + " of " + std::to_string(n) + " points " +
                     (dim == 3 ? "are not within " + std::to_string(max_distance) + " of the surface"
                               : std::string("are outside the domain")) +
                     " (indices " + list + ")");
  }
  py::array_t<double> values(n), gradients({n, py::ssize_t(dim)}), reference({n, py::ssize_t(2)}), distances(n);
  py::array_t<int> cells(n);
  for (py::ssize_t k = 0; k < n; ++k) {
    values.mutable_at(k) = value[k];
    for (int d = 0; d < dim; ++d) gradients.mutable_at(k, d) = gradient(k, d);
    cells.mutable_at(k) = located[k].cell;
    reference.mutable_at(k, 0) = located[k].u, reference.mutable_at(k, 1) = located[k].v;
    distances.mutable_at(k) = located[k].distance;
  }
  py::dict out;
  out["value"] = values;
  out["gradient"] = gradients;
  out["cell"] = cells;
  out["reference"] = reference;
  out["distance"] = distances;
  return out;
}

// The functions alive on a cell, their values and physical gradients at reference points.
py::dict evaluate_basis(const Space& s, long cell_index, py::handle uv) {
  const int cell = s.checked_cell(cell_index);
  const auto p = point_array(uv, 2, "evaluate_basis");
  const py::ssize_t n = p.shape(0);
  for (py::ssize_t k = 0; k < 2 * n; ++k)
    if (!(p.data()[k] >= 0 && p.data()[k] <= 1))
      throw InputError("evaluate_basis: reference coordinates must lie in [0, 1], got " + std::to_string(p.data()[k]));
  Eigen::VectorXd u(n), v(n);
  for (py::ssize_t k = 0; k < n; ++k) u[k] = p.at(k, 0), v[k] = p.at(k, 1);
  CellBasis b;
  {
    py::gil_scoped_release nogil;
    evaluate_cell_basis_at(s.mesh(), s.space->geometry(), cell, u, v, b);
  }
  const std::span<const int> ids = s.mesh().functions(cell);
  const py::ssize_t m = static_cast<py::ssize_t>(ids.size());
  const int dim = b.dimension;
  const Eigen::MatrixXd values = b.value * b.C.transpose();
  py::array_t<double> out_values({n, m}), out_gradient({n, m, py::ssize_t(dim)}), points({n, py::ssize_t(dim)});
  for (py::ssize_t k = 0; k < n; ++k)
    for (py::ssize_t a = 0; a < m; ++a) out_values.mutable_at(k, a) = values(k, a);
  for (int d = 0; d < dim; ++d) {
    const Eigen::MatrixXd g = b.grad(d) * b.C.transpose();
    for (py::ssize_t k = 0; k < n; ++k) {
      for (py::ssize_t a = 0; a < m; ++a) out_gradient.mutable_at(k, a, d) = g(k, a);
      points.mutable_at(k, d) = b.geometry.x(k, d);
    }
  }
  py::dict out;
  out["functions"] = py::array_t<int>(m, ids.data());
  out["value"] = out_values;
  out["gradient"] = out_gradient;
  out["points"] = points;
  return out;
}

py::object json_to_python(const Json& j) { return py::module_::import("json").attr("loads")(j.dump(-1)); }

// ---- the assembled system ----

struct System {
  SharedCase case_;
  SharedErrors errors;
  Ordering ordering = Ordering::kAuto;
  std::shared_ptr<const SplineSpace> space;
  AssembledSystem system;
  const CaseDescription& c() const { return *case_; }
};

// A compressed-row matrix as (data, indices, indptr): views of its arrays, kept alive by `owner`.
py::tuple csr_views(const Eigen::SparseMatrix<double, Eigen::RowMajor>& a, py::handle owner) {
  const py::ssize_t n = a.rows(), nnz = a.nonZeros();
  return py::make_tuple(view(a.valuePtr(), {nnz}, {py::ssize_t(sizeof(double))}, owner),
                        view(a.innerIndexPtr(), {nnz}, {py::ssize_t(sizeof(int))}, owner),
                        view(a.outerIndexPtr(), {n + 1}, {py::ssize_t(sizeof(int))}, owner));
}

}  // namespace
}  // namespace knotwork

PYBIND11_MODULE(_core, m) {
  using namespace knotwork;
  m.doc() = "knotwork's C++ core; use the package `knotwork`, which documents the API.";
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      PyErr_SetString(input_error.ptr(), e.what());
    }
  });

  py::class_<Space>(m, "Space")
      .def_property_readonly("num_functions", [](const Space& s) { return s.mesh().num_functions(); })
      .def_property_readonly("num_cells", [](const Space& s) { return s.mesh().num_cells(); })
      .def_property_readonly("description", [](const Space& s) { return s.space->presentation().description(); })
      .def_property_readonly("family", [](const Space& s) { return s.c().family; })
      .def_property_readonly("degree", [](const Space& s) {
        return py::tuple(py::cast(s.space->degree()));
      })
      .def_property_readonly("is_rational", [](const Space& s) { return s.mesh().is_rational(); })
      .def_property_readonly("notes", [](const Space& s) { return s.space->presentation().notes(); })
      .def("functions", [](py::object self, long cell) {
        const Space& s = self.cast<const Space&>();
        const std::span<const int> f = s.mesh().functions(s.checked_cell(cell));
        return view(f.data(), {py::ssize_t(f.size())}, {py::ssize_t(sizeof(int))}, self);
      })
      .def("extraction", [](py::object self, long cell) {
        const Space& s = self.cast<const Space&>();
        const Eigen::MatrixXd& e = s.mesh().extraction(s.checked_cell(cell));
        return view(e.data(), {py::ssize_t(e.rows()), py::ssize_t(e.cols())},
                    {py::ssize_t(sizeof(double)), py::ssize_t(sizeof(double) * e.rows())}, self);
      })
      .def("weights", [](py::object self) {
        const Space& s = self.cast<const Space&>();
        const Eigen::VectorXd& w = s.mesh().weights();
        return view(w.data(), {py::ssize_t(w.size())}, {py::ssize_t(sizeof(double))}, self);
      })
      .def("cell", [](const Space& s, long cell) {
        const BezierCell& b = s.mesh().cell(s.checked_cell(cell));
        py::dict d;
        d["patch"] = b.patch;
        // A hexahedron (dimension 3) has a third degree, a third interval and six sides.
        const bool volume = b.dimension == 3;
        d["degree"] = volume ? py::make_tuple(b.degree_u, b.degree_v, int{b.degree_w}) : py::make_tuple(b.degree_u, b.degree_v);
        d["parameter_box"] = volume ? py::make_tuple(b.u0, b.u1, b.v0, b.v1, b.w0, b.w1) : py::make_tuple(b.u0, b.u1, b.v0, b.v1);
        py::list sides;
        for (int side = 0; side < b.num_sides(); ++side) {
          const int id = b.boundary[side];
          sides.append(id < 0 ? py::object(py::none())
                              : py::object(py::str(id < int(s.mesh().boundary_names().size())
                                                       ? s.mesh().boundary_names()[id]
                                                       : std::to_string(id))));
        }
        d["boundary"] = sides;
        return d;
      })
      .def("partition_of_unity_error", [](const Space& s) {
        py::gil_scoped_release nogil;
        return partition_of_unity_error(s.mesh());
      })
      .def("rank", [](const Space& s) -> py::object {
        long r;
        {
          py::gil_scoped_release nogil;
          r = bezier_rank(s.mesh());
        }
        return r < 0 ? py::object(py::none()) : py::object(py::int_(r));
      })
      .def("evaluate_basis", [](const Space& s, long cell, py::handle uv) { return evaluate_basis(s, cell, uv); })
      .def("report", [](const Space& s) {
        std::optional<Json> j;
        {
          py::gil_scoped_release nogil;
          j.emplace(basis_json(s.c(), *s.space));
        }
        return json_to_python(*j);
      });

  py::class_<Run>(m, "Run")
      .def("summary", [](const Run& r) { return json_to_python(run_json(r.c(), *r.outcome)); })
      .def_property_readonly("coefficients", [](py::object self) {
        const Eigen::VectorXd& x = self.cast<const Run&>().outcome->solution.coefficients;
        return view(x.data(), {py::ssize_t(x.size())}, {py::ssize_t(sizeof(double))}, self);
      })
      .def_property_readonly("cell_h1_error_squared", [](py::object self) {
        const Eigen::VectorXd& x = self.cast<const Run&>().outcome->solution.cell_h1_squared;
        return view(x.data(), {py::ssize_t(x.size())}, {py::ssize_t(sizeof(double))}, self);
      })
      .def_property_readonly("space", [](const Run& r) {
        return Space{r.case_, std::shared_ptr<const SplineSpace>(r.outcome, r.outcome->space.get())};
      })
      .def("sample", [](const Run& r, int n) {
        py::dict d = sample(r.c(), *r.outcome->space, r.outcome->solution, n);
        if (r.errors) r.errors->raise();
        return d;
      })
      .def("evaluate", [](Run& r, py::handle points, py::object distance) { return evaluate_solution(r, points, distance); })
      .def("write_paraview", [](const Run& r, py::object directory) {
        const std::string dir = *output_of(directory);
        std::optional<OutputStage> stage;
        {
          py::gil_scoped_release nogil;
          stage.emplace(dir);
          write_run_output(r.c(), *r.outcome->space, r.outcome->solution, *stage);
        }
        // The files hold the exact solution too: a Python function that raised leaves none.
        if (r.errors) r.errors->raise();
        py::gil_scoped_release nogil;
        return stage->commit();
      });

  m.def("run", [](py::object case_, const std::string& name, py::dict overrides, py::object output, py::object progress) {
    Ordering ordering;
    SharedErrors errors;
    const SharedCase c = std::make_shared<const CaseDescription>(prepared_case(case_, name, overrides, &ordering, &errors));
    const std::optional<std::string> out = output_of(output);
    PythonHooks hooks(progress, errors);
    auto outcome = hooks.call([&](const ProgressFunction& p) {
      return std::make_shared<RunOutcome>(run_study(*c, ordering, out ? &*out : nullptr, p));
    });
    return Run{c, std::move(outcome), errors, nullptr};
  });

  py::class_<System>(m, "System")
      .def_property_readonly("num_functions", [](const System& s) { return s.space->mesh().num_functions(); })
      .def("stiffness_csr", [](py::object self) { return csr_views(self.cast<const System&>().system.stiffness, self); })
      .def("mass_csr", [](py::object self) { return csr_views(self.cast<const System&>().system.mass, self); })
      .def_property_readonly("load", [](py::object self) {
        const Eigen::VectorXd& x = self.cast<const System&>().system.load;
        return view(x.data(), {py::ssize_t(x.size())}, {py::ssize_t(sizeof(double))}, self);
      })
      .def_property_readonly("dirichlet", [](py::object self) {
        const std::vector<int>& d = self.cast<const System&>().system.dirichlet;
        return view(d.data(), {py::ssize_t(d.size())}, {py::ssize_t(sizeof(int))}, self);
      })
      .def_property_readonly("dirichlet_values", [](py::object self) {
        const Eigen::VectorXd& x = self.cast<const System&>().system.dirichlet_values;
        return view(x.data(), {py::ssize_t(x.size())}, {py::ssize_t(sizeof(double))}, self);
      })
      .def_property_readonly("zero_mean", [](const System& s) { return s.system.zero_mean; })
      .def_property_readonly("space", [](const System& s) { return Space{s.case_, s.space}; })
      .def("solve", [](const System& s, py::object progress) {
        PythonHooks hooks(progress, s.errors);
        Eigen::VectorXd x = hooks.call([&](const ProgressFunction& p) {
          return solve_case(s.c(), *s.space, s.ordering, p).coefficients;
        });
        return py::array_t<double>(x.size(), x.data());
      });

  m.def("system", [](py::object case_, const std::string& name, py::dict overrides, py::object progress) {
    Ordering ordering;
    SharedErrors errors;
    const SharedCase c = std::make_shared<const CaseDescription>(prepared_case(case_, name, overrides, &ordering, &errors));
    PythonHooks hooks(progress, errors);
    return hooks.call([&](const ProgressFunction& p) {
      System s{c, errors, ordering, std::shared_ptr<const SplineSpace>(build_space(*c, 0, p)), {}};
      s.system = assemble_system(*c, *s.space, p);
      return s;
    });
  });

  m.def("converge", [](py::object case_, const std::string& name, int levels, py::dict overrides, py::object output,
                       py::object progress) {
    Ordering ordering;
    SharedErrors errors;
    const CaseDescription c = prepared_case(case_, name, overrides, &ordering, &errors);
    const std::optional<std::string> out = output_of(output);
    PythonHooks hooks(progress, errors);
    const Json j = hooks.call([&](const ProgressFunction& p) {
      return converge_study(c, levels, ordering, out ? &*out : nullptr, p).json;
    });
    return json_to_python(j);
  });

  m.def("adapt", [](py::object case_, const std::string& name, py::dict overrides, int steps, double theta, long max_dofs,
                    py::object output, int output_every, py::object progress) {
    Ordering ordering;
    SharedErrors errors;
    CaseDescription c = prepared_case(case_, name, overrides, &ordering, &errors);
    if (steps) c.adapt.steps = steps;
    if (theta) c.adapt.theta = theta;
    if (max_dofs) c.adapt.max_dofs = max_dofs;
    const std::optional<std::string> out = output_of(output);
    PythonHooks hooks(progress, errors);
    const Json j = hooks.call([&](const ProgressFunction& p) {
      return adapt_study(c, ordering, out ? &*out : nullptr, p, output_every).json;
    });
    return json_to_python(j);
  });

  m.def("space", [](py::object case_, const std::string& name, py::dict overrides, py::object progress) {
    const SharedCase c = std::make_shared<const CaseDescription>(prepared_case(case_, name, overrides, nullptr));
    PythonHooks hooks(progress);
    std::shared_ptr<const SplineSpace> s =
        hooks.call([&](const ProgressFunction& p) { return std::shared_ptr<const SplineSpace>(build_space(*c, 0, p)); });
    return Space{c, std::move(s)};
  });

  m.def("dimension", [](py::object tmesh, const std::string& name, bool exact) {
    PartitionDescription p;
    std::string file = name;
    if (py::isinstance<py::dict>(tmesh)) {
      p = load_partition_document(to_document(tmesh, name, "", 0), name);
    } else {
      file = py::module_::import("os").attr("fspath")(tmesh).cast<std::string>();
      p = load_partition(file);
    }
    std::optional<Json> j;
    {
      py::gil_scoped_release nogil;
      j.emplace(dimension_json(p, file, exact));
    }
    return json_to_python(*j);
  });

  // OpenBLAS reads OPENBLAS_NUM_THREADS when it is loaded, which may have happened (numpy)
  // before knotwork is imported: the package sets it through the library too.
  m.def("set_blas_threads", [](int n) { openblas_set_num_threads(n); });
  // The kernel OpenBLAS runs, and the one to name in OPENBLAS_CORETYPE where it took this CPU
  // for a generic one (solver/blas_kernel.cpp; the package asks a fresh process, before
  // OpenBLAS loads here).
  m.def("blas_kernel", &knotwork::blas_kernel);
  m.def("better_blas_kernel", &knotwork::better_blas_kernel);
}
