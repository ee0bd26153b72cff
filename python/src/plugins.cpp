// Plugins written in Python: kernels, targets and centre placements registered at run time
// into the same registries as the C++ plugins (python/rkhs_study/plugins.py is the Python
// side, docs/python.md the contract).
//
// A Python plugin is reached through an object its factory made (PluginEntry::factory):
//   kernel     k(X, Y) -> (m, n) array, diagonal(X) -> (m,), properties() -> dict of
//              KernelProperties' fields;
//   target     f(X) -> (m,), derivative(X) -> (m,) when has_derivative is true;
//   placement  place(n, domain, seed) -> (n, d) array.
// X and Y are (m, d) float64 arrays of points (d = the domain's dimension). The kernel is wrapped
// in KernelModel<PythonKernel>, a BlockKernel (kernel/kernel_algorithms.hpp): a Gram matrix,
// a chunk of a cross matrix or a basis evaluation is one Python call, not one per value.
//
// The GIL: every call into Python takes it (py::gil_scoped_acquire) and holds it for that call
// only, so trials run on worker threads whose other work (factorisations, solves, C++ kernels)
// runs in parallel while Python calls take turns. The module releases the GIL while a study runs
// (module.cpp), so a worker never waits for a thread that waits for it. A Python exception
// becomes std::runtime_error with the plugin's name and the exception's text: the trial fails
// with that reason and the study goes on.
//
// Identity: the plugins of one Python class are recorded as a host module (plugin_loader.hpp,
// record_host_plugins) whose hash is the hash of the class's source, so a changed class re-runs
// the trials a result store holds for it.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "rkhs/approx/centres.hpp"
#include "rkhs/approx/target.hpp"
#include "rkhs/core/build_info.hpp"
#include "rkhs/kernel/kernel.hpp"
#include "rkhs/kernel/kernel_algorithms.hpp"
#include "rkhs/plugin/module.hpp"
#include "rkhs/plugin/plugin_kinds.hpp"
#include "rkhs/plugin/plugin_loader.hpp"
#include "rkhs/verify/plugin_verification.hpp"

namespace py = pybind11;

namespace rkhs::python {
namespace {

// A Python object shared by C++ objects that may be destroyed on any thread: the last owner
// takes the GIL to release it (or leaks it once the interpreter has finalised).
using SharedObject = std::shared_ptr<py::object>;

SharedObject share(py::object object) {
  return SharedObject(new py::object(std::move(object)), [](py::object* p) {
    if (!Py_IsInitialized()) {
      p->release();
      delete p;
      return;
    }
    py::gil_scoped_acquire gil;
    delete p;
  });
}

// "ValueError: message (at file.py:12 in k)": the exception and the innermost frame of its
// traceback, one line for a trial's reason. Called with the GIL held.
std::string exception_text(py::error_already_set& e) {
  std::string text = py::str(e.type().attr("__name__")).cast<std::string>();
  if (const auto message = py::str(e.value()).cast<std::string>(); !message.empty())
    text += ": " + message;
  py::object frame = py::none();
  for (py::object tb = py::reinterpret_borrow<py::object>(e.trace()); !tb.is_none();
       tb = tb.attr("tb_next"))
    frame = tb;
  if (!frame.is_none()) {
    const py::object code = frame.attr("tb_frame").attr("f_code");
    text += " (at " + py::str(code.attr("co_filename")).cast<std::string>() + ":" +
            py::str(frame.attr("tb_lineno")).cast<std::string>() + " in " +
            py::str(code.attr("co_name")).cast<std::string>() + ")";
  }
  return text;
}

// Calls `call` with the GIL held; a Python exception becomes std::runtime_error naming `what`.
template <class Call>
auto with_python(const std::string& what, Call&& call) {
  py::gil_scoped_acquire gil;
  try {
    return call();
  } catch (py::error_already_set& e) {
    throw std::runtime_error(what + " raised " + exception_text(e));
  } catch (const py::cast_error& e) {
    throw std::runtime_error(what + " returned a value of the wrong type: " + e.what());
  }
}

// Points (flat, d coordinates each) as an (m, d) float64 array.
py::array_t<double> point_array(std::span<const double> points, int dimension) {
  const auto d = static_cast<py::ssize_t>(dimension);
  const auto m = static_cast<py::ssize_t>(points.size()) / d;
  py::array_t<double> array({m, d});
  if (!points.empty())
    std::memcpy(array.mutable_data(), points.data(), points.size() * sizeof(double));
  return array;
}

// `result` as a C-ordered float64 array of exactly `shape`; std::runtime_error naming `what`
// and the shape found otherwise.
py::array_t<double> checked_array(py::handle result, std::vector<py::ssize_t> shape,
                                  const std::string& what) {
  auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(result);
  if (!array)
    throw std::runtime_error(what + " returned " + std::string(py::str(py::type::of(result))) +
                             ", expected a float array");
  bool same = array.ndim() == static_cast<py::ssize_t>(shape.size());
  for (std::size_t a = 0; same && a < shape.size(); ++a)
    same = array.shape(static_cast<py::ssize_t>(a)) == shape[a];
  if (!same) {
    std::string found = "(", expected = "(";
    for (py::ssize_t a = 0; a < array.ndim(); ++a)
      found += (a ? ", " : "") + std::to_string(array.shape(a));
    for (std::size_t a = 0; a < shape.size(); ++a)
      expected += (a ? ", " : "") + std::to_string(shape[a]);
    throw std::runtime_error(what + " returned an array of shape " + found +
                             (shape.size() == 1 ? ",)" : ")") + ", expected " + expected +
                             (shape.size() == 1 ? ",)" : ")"));
  }
  return array;
}

py::dict domain_dict(const Domain& domain) {
  py::dict d;
  d["length"] = domain.length;
  d["width"] = domain.width;
  d["height"] = domain.height;
  d["periodic"] = domain.periodic;
  d["dimension"] = domain.dimension;
  return d;
}

py::dict parameter_dict(const ParameterSet& parameters) {
  py::dict d;
  for (const auto& [name, value] : parameters.values())
    std::visit([&, &key = name](const auto& v) { d[py::str(key)] = v; }, value);
  return d;
}

// A kernel written in Python, for KernelModel<PythonKernel> (a BlockKernel).
class PythonKernel {
 public:
  // Only for the KernelFunction concept: each registered Python kernel is named by name().
  static PluginInfo info() { return {"python", "a kernel written in Python", {}}; }

  PythonKernel(const ParameterSet& parameters, const Domain& domain, const std::string& name,
               const SharedObject& factory)
      : name_(name), domain_(domain) {
    with_python("kernel '" + name_ + "'", [&] {
      object_ = share((*factory)(domain_dict(domain), parameter_dict(parameters)));
      const py::dict p = (*object_).attr("properties")();
      properties_.positive_definite = p["positive_definite"].cast<bool>();
      if (!p["sobolev_order"].is_none())
        properties_.sobolev_order = p["sobolev_order"].cast<double>();
      properties_.analytic = p["analytic"].cast<bool>();
      properties_.support_radius = p["support_radius"].cast<double>();
      properties_.stationary = p["stationary"].cast<bool>();
      properties_.periodic = p["periodic"].cast<bool>();
      properties_.dimension = p["dimension"].cast<int>();
    });
    if (properties_.dimension != domain.dimension)
      throw std::invalid_argument("kernel '" + name_ + "': properties() gives dimension " +
                                  std::to_string(properties_.dimension) +
                                  " on a domain of dimension " + std::to_string(domain.dimension));
  }

  const std::string& name() const noexcept { return name_; }
  KernelProperties properties() const { return properties_; }

  double operator()(double x, double y) const { return value(&x, &y); }
  double operator()(const double* x, const double* y) const { return value(x, y); }

  void block(std::span<const double> a, std::span<const double> b,
             Eigen::Ref<Eigen::MatrixXd> out) const {
    const auto rows = static_cast<py::ssize_t>(domain_.point_count(a));
    const auto cols = static_cast<py::ssize_t>(domain_.point_count(b));
    const std::string what = "kernel '" + name_ + "': k(X, Y)";
    with_python(what, [&] {
      const py::object result = (*object_).attr("k")(point_array(a, domain_.dimension),
                                                     point_array(b, domain_.dimension));
      const auto array = checked_array(result, {rows, cols}, what);
      const auto view = array.unchecked<2>();
      for (py::ssize_t i = 0; i < rows; ++i)
        for (py::ssize_t j = 0; j < cols; ++j) out(i, j) = view(i, j);
    });
  }

  void diagonal(std::span<const double> points, std::span<double> out) const {
    const std::string what = "kernel '" + name_ + "': diagonal(X)";
    with_python(what, [&] {
      const py::object result = (*object_).attr("diagonal")(point_array(points, domain_.dimension));
      const auto array = checked_array(result, {static_cast<py::ssize_t>(out.size())}, what);
      std::memcpy(out.data(), array.data(), out.size() * sizeof(double));
    });
  }

 private:
  double value(const double* x, const double* y) const {
    const auto d = static_cast<std::size_t>(domain_.dimension);
    double result = 0;
    block(std::span<const double>(x, d), std::span<const double>(y, d),
          Eigen::Map<Eigen::MatrixXd>(&result, 1, 1));
    return result;
  }

  std::string name_;
  Domain domain_;
  SharedObject object_;
  KernelProperties properties_;
};

static_assert(BlockKernel<PythonKernel> && PointKernel<PythonKernel>);

class PythonTarget final : public TargetFunction {
 public:
  PythonTarget(const ParameterSet& parameters, const Domain& domain, const std::string& name,
               const SharedObject& factory)
      : name_(name), domain_(domain) {
    with_python("target '" + name_ + "'", [&] {
      object_ = share((*factory)(domain_dict(domain), parameter_dict(parameters)));
      exact_derivative_ = (*object_).attr("has_derivative").cast<bool>();
    });
  }

  void evaluate(std::span<const double> points, std::span<double> out) const override {
    call("f", points, out);
  }
  void derivative(std::span<const double> points, std::span<double> out) const override {
    if (exact_derivative_)
      call("derivative", points, out);
    else
      TargetFunction::derivative(points, out);
  }
  bool has_exact_derivative() const override { return exact_derivative_; }

 private:
  void call(const char* method, std::span<const double> points, std::span<double> out) const {
    const std::string what = "target '" + name_ + "': " + method + "(X)";
    with_python(what, [&] {
      const py::object result = (*object_).attr(method)(point_array(points, domain_.dimension));
      const auto array = checked_array(result, {static_cast<py::ssize_t>(out.size())}, what);
      std::memcpy(out.data(), array.data(), out.size() * sizeof(double));
    });
  }

  std::string name_;
  Domain domain_;
  SharedObject object_;
  bool exact_derivative_ = false;
};

class PythonPlacement final : public CentrePlacement {
 public:
  PythonPlacement(const ParameterSet& parameters, const std::string& name,
                  const SharedObject& factory)
      : name_(name) {
    with_python("centres '" + name_ + "'",
                [&] { object_ = share((*factory)(parameter_dict(parameters))); });
  }

  void place_into(const Domain& domain, std::uint64_t trial_seed,
                  std::span<double> out) const override {
    const auto d = static_cast<std::size_t>(domain.dimension);
    const std::size_t n = out.size() / d;
    const std::string what = "centres '" + name_ + "': place(" + std::to_string(n) + ", domain)";
    with_python(what, [&] {
      const py::object result = (*object_).attr("place")(n, domain_dict(domain), trial_seed);
      const auto array =
          checked_array(result, {static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(d)}, what);
      std::memcpy(out.data(), array.data(), out.size() * sizeof(double));
    });
    for (std::size_t i = 0; i < out.size(); ++i) {
      const int axis = static_cast<int>(i % d);
      const double x = out[i], extent = domain.extent(axis);
      if (!(x >= 0 && (domain.periodic ? x < extent : x <= extent)))
        throw std::runtime_error(what + ": coordinate " + std::to_string(axis + 1) + " of centre " +
                                 std::to_string(i / d + 1) + " is " + format_real(x) +
                                 ", outside " + domain.describe());
    }
  }

 private:
  std::string name_;
  SharedObject object_;
};

ParameterSpec parameter_spec(const py::dict& d) {
  ParameterSpec spec;
  spec.name = d["name"].cast<std::string>();
  const auto type = d["type"].cast<std::string>();
  spec.doc = d["doc"].cast<std::string>();
  if (type == "real") {
    spec.type = ParameterType::real;
    spec.default_value = d["default"].cast<double>();
  } else if (type == "integer") {
    spec.type = ParameterType::integer;
    spec.default_value = d["default"].cast<std::int64_t>();
  } else if (type == "boolean") {
    spec.type = ParameterType::boolean;
    spec.default_value = d["default"].cast<bool>();
  } else if (type == "choice") {
    spec.type = ParameterType::choice;
    spec.default_value = d["default"].cast<std::string>();
    spec.choices = d["choices"].cast<std::vector<std::string>>();
  } else if (type == "text") {
    spec.type = ParameterType::text;
    spec.default_value = d["default"].cast<std::string>();
  } else {
    throw std::invalid_argument("parameter '" + spec.name + "': unknown type '" + type + "'");
  }
  if (!d["min"].is_none()) spec.min = d["min"].cast<double>();
  if (!d["max"].is_none()) spec.max = d["max"].cast<double>();
  spec.min_exclusive = d["min_exclusive"].cast<bool>();
  spec.max_exclusive = d["max_exclusive"].cast<bool>();
  return spec;
}

PluginInfo plugin_info(const py::dict& d) {
  PluginInfo info;
  info.name = d["name"].cast<std::string>();
  info.doc = d["doc"].cast<std::string>();
  for (const auto& p : d["parameters"].cast<py::list>())
    info.parameters.push_back(parameter_spec(p.cast<py::dict>()));
  info.traits.emplace_back("written in", "Python");
  return info;
}

// Registers `info` into `Kind`'s registry under the host record `origin` (replacing what that
// origin registered before). Throws std::invalid_argument with the registry's reason when the
// registration is refused (a name taken by another plugin, an invalid parameter declaration).
template <class Kind>
void register_host_plugin(PluginInfo info, typename Kind::Registry::Factory factory,
                          const std::string& origin, const std::string& sha256) {
  forget_host_plugins(origin);
  auto& registry = Kind::registry();
  registry.unfreeze();  // between runs only: a run freezes it again (study_pipeline.cpp)
  const auto name = info.name;
  const auto errors_before = registry.error_count();
  if (!registry.add(std::move(info), std::move(factory))) {
    const auto errors = registry.take_errors_after(errors_before);
    throw std::invalid_argument(errors.empty() ? std::string(Kind::singular) + " '" + name +
                                                     "' was not registered"
                                               : errors.front());
  }
  LoadedPlugin record;
  record.file = origin;
  record.sha256 = sha256;
  record.name = origin;
  record.rkhs_study_version = build_info().version;
  record.abi_version = RKHS_PLUGIN_ABI_VERSION;
  record.build_configuration =
      "Python (registered at run time; keyed by the SHA-256 " + sha256 + " of its source)";
  for_each_plugin_kind(
      [&](auto kind) { record.registered[std::string(decltype(kind)::singular)] = {}; });
  record.registered[std::string(Kind::singular)] = {name};
  record_host_plugins(std::move(record));
}

}  // namespace

void bind_plugins(py::module_& m) {
  m.def(
      "register_kernel",
      [](const py::dict& info, py::object factory, const std::string& origin,
         const std::string& sha256) {
        auto parsed = plugin_info(info);
        const auto shared = share(std::move(factory));
        const auto name = parsed.name;
        register_host_plugin<KernelKind>(
            std::move(parsed),
            [name, shared](const ParameterSet& parameters, const Domain& domain) {
              return std::unique_ptr<AnyKernel>(
                  std::make_unique<KernelModel<PythonKernel>>(parameters, domain, name, shared));
            },
            origin, sha256);
      },
      py::arg("info"), py::arg("factory"), py::arg("origin"), py::arg("sha256"),
      "Registers a kernel written in Python: factory(domain, parameters) makes the object whose "
      "k, diagonal and properties the kernel calls");
  m.def(
      "register_target",
      [](const py::dict& info, py::object factory, const std::string& origin,
         const std::string& sha256) {
        auto parsed = plugin_info(info);
        const auto shared = share(std::move(factory));
        const auto name = parsed.name;
        register_host_plugin<TargetKind>(
            std::move(parsed),
            [name, shared](const ParameterSet& parameters, const Domain& domain) {
              return std::unique_ptr<TargetFunction>(
                  std::make_unique<PythonTarget>(parameters, domain, name, shared));
            },
            origin, sha256);
      },
      py::arg("info"), py::arg("factory"), py::arg("origin"), py::arg("sha256"),
      "Registers a target written in Python: factory(domain, parameters) makes the object whose "
      "f (and derivative) the target calls");
  m.def(
      "register_centres",
      [](const py::dict& info, py::object factory, const std::string& origin,
         const std::string& sha256) {
        auto parsed = plugin_info(info);
        const auto shared = share(std::move(factory));
        const auto name = parsed.name;
        register_host_plugin<CentresKind>(
            std::move(parsed),
            [name, shared](const ParameterSet& parameters) {
              return std::unique_ptr<CentrePlacement>(
                  std::make_unique<PythonPlacement>(parameters, name, shared));
            },
            origin, sha256);
      },
      py::arg("info"), py::arg("factory"), py::arg("origin"), py::arg("sha256"),
      "Registers a centre placement written in Python: factory(parameters) makes the object "
      "whose place(n, domain, seed) the placement calls");
  m.def(
      "unregister", [](const std::string& origin) { return forget_host_plugins(origin); },
      py::arg("origin"), "Removes the plugins registered under `origin`; False when none");
  m.def(
      "verify_kernel",
      [](const std::string& name) {
        PluginVerification verification;
        {
          py::gil_scoped_release release;
          verification.kernels.push_back(verify_kernel(name));
        }
        for (const auto& plugin : loaded_plugins()) {
          const auto it = plugin.registered.find(std::string(KernelKind::singular));
          if (it != plugin.registered.end() &&
              std::find(it->second.begin(), it->second.end(), name) != it->second.end())
            verification.plugin = plugin;
        }
        return std::make_pair(verification.passed(), format_verification(verification));
      },
      py::arg("name"),
      "The kernel contract and declared theory of the registered kernel `name` (as "
      "`rkhs-study verify-plugin` checks a module's kernels): (passed, report)");
  m.def(
      "kernel_matrix",
      [](const std::string& name, const py::dict& parameters, const py::dict& domain,
         const py::array_t<double, py::array::c_style | py::array::forcecast>& x,
         const py::array_t<double, py::array::c_style | py::array::forcecast>& y) {
        Domain omega;
        omega.length = domain["length"].cast<double>();
        omega.width = domain["width"].cast<double>();
        omega.height = domain["height"].cast<double>();
        omega.periodic = domain["periodic"].cast<bool>();
        omega.dimension = domain["dimension"].cast<int>();
        std::map<std::string, ParameterValue> given;
        for (const auto& [key, value] : parameters) {
          const auto k = key.cast<std::string>();
          if (py::isinstance<py::bool_>(value))
            given[k] = value.cast<bool>();
          else if (py::isinstance<py::int_>(value))
            given[k] = value.cast<std::int64_t>();
          else if (py::isinstance<py::float_>(value))
            given[k] = value.cast<double>();
          else
            given[k] = value.cast<std::string>();
        }
        const auto* entry = kernel_registry().find(name);
        if (!entry) throw std::invalid_argument("unknown kernel '" + name + "'");
        const auto resolved = ParameterSet::resolve(entry->info.parameters, given);
        std::vector<double> a(x.data(), x.data() + x.size()), b(y.data(), y.data() + y.size());
        Eigen::MatrixXd out;
        {
          py::gil_scoped_release release;
          const auto kernel = make_kernel(name, resolved, omega);
          out = kernel->cross(a, b);
        }
        py::array_t<double> result({out.rows(), out.cols()});
        auto view = result.mutable_unchecked<2>();
        for (Eigen::Index i = 0; i < out.rows(); ++i)
          for (Eigen::Index j = 0; j < out.cols(); ++j) view(i, j) = out(i, j);
        return result;
      },
      py::arg("name"), py::arg("parameters"), py::arg("domain"), py::arg("x"), py::arg("y"),
      "k(x_i, y_j) of the registered kernel `name` (C++ or Python) with `parameters` on "
      "`domain`: the cross matrix a trial computes");
}

}  // namespace rkhs::python
