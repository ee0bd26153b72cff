#include "rkhs/plugin/plugin_loader.hpp"

#include <dlfcn.h>
#include <elf.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <mutex>

#include "rkhs/core/build_info.hpp"
#include "rkhs/core/input_file.hpp"
#include "rkhs/core/sha256.hpp"
#include "rkhs/plugin/build_configuration.hpp"
#include "rkhs/plugin/module.hpp"
#include "rkhs/plugin/plugin_kinds.hpp"

namespace rkhs {

namespace {

namespace fs = std::filesystem;

// What the registries hold, per kind (keyed by the kind's singular name), to learn what a
// module registered and whether it was refused.
struct RegistryState {
  std::map<std::string, std::vector<std::string>, std::less<>> names;
  std::map<std::string, std::size_t, std::less<>> errors;

  static RegistryState take() {
    RegistryState out;
    for_each_plugin_kind([&](auto kind) {
      using Kind = decltype(kind);
      out.names[std::string(Kind::singular)] = Kind::registry().names();
      out.errors[std::string(Kind::singular)] = Kind::registry().error_count();
    });
    return out;
  }
  bool same_errors(const RegistryState& other) const { return errors == other.errors; }
  bool same(const RegistryState& other) const { return names == other.names && same_errors(other); }
};

std::vector<std::string> added(const std::vector<std::string>& before,
                               const std::vector<std::string>& after) {
  std::vector<std::string> out;
  std::set_difference(after.begin(), after.end(), before.begin(), before.end(),
                      std::back_inserter(out));
  return out;
}

// Removes `registered` (per kind, as in LoadedPlugin::registered) from the registries.
void remove_all(const std::map<std::string, std::vector<std::string>, std::less<>>& registered) {
  for_each_plugin_kind([&](auto kind) {
    using Kind = decltype(kind);
    if (const auto it = registered.find(Kind::singular); it != registered.end())
      for (const auto& name : it->second) Kind::registry().remove(name);
  });
}

// Removes what was registered since `before` and returns the registration errors recorded since.
std::vector<std::string> roll_back(const RegistryState& before) {
  const auto now = RegistryState::take();
  std::vector<std::string> errors;
  for_each_plugin_kind([&](auto kind) {
    using Kind = decltype(kind);
    const std::string key(Kind::singular);
    for (const auto& name : added(before.names.at(key), now.names.at(key)))
      Kind::registry().remove(name);
    const auto taken = Kind::registry().take_errors_after(before.errors.at(key));
    errors.insert(errors.end(), taken.begin(), taken.end());
  });
  return errors;
}

struct Module {
  LoadedPlugin plugin;
  void* handle = nullptr;  // closed only by unload_plugin: the registries hold its factories;
                           // null for a host's plugins (record_host_plugins)
};

std::mutex& loader_mutex() {
  static std::mutex mutex;
  return mutex;
}
std::vector<Module>& modules() {
  static std::vector<Module> loaded;
  return loaded;
}

template <class Function>
Function* symbol(void* handle, const char* name) {
  return reinterpret_cast<Function*>(dlsym(handle, name));
}

// Whether `file` (a regular file) is a complete ELF shared object, read with pread before
// dlopen maps it: the dynamic loader maps its segments and reads them, and a segment that lies
// beyond the end of the file is a SIGBUS in dlopen (a truncated .so). Returns an empty string
// when it is, or when it is no ELF file of this machine's class and byte order at all (dlopen
// then refuses it with its own reason, "invalid ELF header", "wrong ELF class"); otherwise why
// not: the headers, the section headers and every segment must lie within the file.
std::string incomplete_elf(const fs::path& file) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) return fmt::format("cannot be opened: {}", std::strerror(errno));
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat info {};
  if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) return "not a regular file";
  const auto size = static_cast<std::uint64_t>(info.st_size);
  auto read_at = [&](void* into, std::size_t bytes, std::uint64_t offset) {
    return offset <= size && bytes <= size - offset &&
           ::pread(fd, into, bytes, static_cast<off_t>(offset)) == static_cast<ssize_t>(bytes);
  };
  unsigned char ident[EI_NIDENT] = {};
  if (!read_at(ident, sizeof ident, 0) || std::memcmp(ident, ELFMAG, SELFMAG) != 0 ||
      ident[EI_CLASS] != ELFCLASS64)
    return {};
#if __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  if (ident[EI_DATA] != ELFDATA2LSB) return {};
#else
  if (ident[EI_DATA] != ELFDATA2MSB) return {};
#endif
  const auto need = [&](std::uint64_t bytes, std::string_view what) {
    return fmt::format("not a complete shared library: {} bytes, its {} need{} {}", size, what,
                       what.back() == 's' ? "" : "s", bytes);
  };
  Elf64_Ehdr header{};
  if (!read_at(&header, sizeof header, 0)) return need(sizeof header, "ELF header");
  if (header.e_type != ET_DYN) return {};  // dlopen: "cannot dynamically load executable"
  // Sums of 64-bit offsets and counts below 2^16 times sizes below 2^16: no overflow unless an
  // offset is within 2^32 of 2^64, which no file size reaches either.
  const auto table_end = [](std::uint64_t offset, std::uint64_t count, std::uint64_t entry) {
    const std::uint64_t bytes = count * entry;
    return offset > UINT64_MAX - bytes ? UINT64_MAX : offset + bytes;
  };
  if (header.e_phnum == 0 || header.e_phentsize != sizeof(Elf64_Phdr)) return {};
  const std::uint64_t headers_end = table_end(header.e_phoff, header.e_phnum, header.e_phentsize);
  if (headers_end > size) return need(headers_end, "program headers");
  if (header.e_shoff != 0) {
    const std::uint64_t sections_end =
        table_end(header.e_shoff, header.e_shnum, header.e_shentsize);
    if (sections_end > size) return need(sections_end, "section headers");
  }
  std::uint64_t segments_end = 0;
  for (std::uint16_t i = 0; i < header.e_phnum; ++i) {
    Elf64_Phdr segment{};
    if (!read_at(&segment, sizeof segment, header.e_phoff + i * std::uint64_t{sizeof segment}))
      return need(headers_end, "program headers");
    if (segment.p_type == PT_NULL) continue;
    segments_end = std::max(segments_end, table_end(segment.p_offset, 1, segment.p_filesz));
  }
  if (segments_end > size) return need(segments_end, "program headers");
  return {};
}

}  // namespace

LoadedPlugin load_plugin(const fs::path& file) {
  std::lock_guard lock(loader_mutex());
  const std::string shown = file.string();
  std::error_code error;
  if (!fs::exists(file, error)) throw PluginError(shown + ": plugin file not found");
  if (fs::is_directory(file, error))
    throw PluginError(shown + ": is a directory, not a plugin file");
  const fs::path canonical = fs::canonical(file, error);
  if (error)
    throw PluginError(fmt::format("{}: cannot resolve the path: {}", shown, error.message()));
  for (const auto& module : modules())
    if (module.plugin.file == canonical) return module.plugin;
  // By type, before anything opens it (opening a FIFO waits for a writer), then by its ELF
  // headers (a truncated library is a SIGBUS inside dlopen).
  if (const auto type = fs::status(canonical, error).type(); type != fs::file_type::regular)
    throw PluginError(
        fmt::format("{}: is {}, not a plugin file (a shared library)", shown, file_kind(type)));
  if (const auto why = incomplete_elf(canonical); !why.empty())
    throw PluginError(fmt::format("{}: not an rkhs-study plugin ({})", shown, why));
  // The bytes that will be mapped, hashed once: what the trials it computes are keyed by.
  std::string content_hash;
  try {
    content_hash = sha256_file(canonical);
  } catch (const std::exception& e) {
    throw PluginError(fmt::format("{}: not an rkhs-study plugin ({})", shown, e.what()));
  }

  const auto before = RegistryState::take();
  dlerror();
  // Lazy binding: see plugin/module.hpp (a module built against another ABI still loads far enough
  // to say which ABI it was built against). Local: its symbols do not leak into other modules.
  void* handle = dlopen(canonical.c_str(), RTLD_LAZY | RTLD_LOCAL);
  if (!handle) {
    const char* why = dlerror();
    roll_back(before);
    throw PluginError(
        fmt::format("{}: not an rkhs-study plugin (cannot be loaded as a shared "
                    "library: {})",
                    shown, why ? why : "unknown reason"));
  }
  auto fail = [&](const std::string& message) {
    roll_back(before);
    dlclose(handle);
    throw PluginError(shown + ": " + message);
  };

  auto* abi_version = symbol<int() noexcept>(handle, "rkhs_plugin_abi_version");
  if (!abi_version)
    fail(
        "not an rkhs-study plugin (it exports no rkhs_plugin_abi_version; declare the module "
        "with RKHS_PLUGIN_MODULE(name) from rkhs/plugin/module.hpp)");
  auto* version = symbol<const char*() noexcept>(handle, "rkhs_plugin_rkhs_study_version");
  const std::string built_with = version && version() ? version() : "unknown version";
  const int abi = abi_version();
  if (abi != RKHS_PLUGIN_ABI_VERSION)
    fail(
        fmt::format("built against plugin ABI {} (rkhs-study {}), this rkhs-study {} has plugin "
                    "ABI {}; rebuild the plugin against this rkhs-study",
                    abi, built_with, build_info().version, RKHS_PLUGIN_ABI_VERSION));
  auto* configuration_of =
      symbol<const BuildConfiguration*() noexcept>(handle, "rkhs_plugin_build_configuration");
  const BuildConfiguration* configuration = configuration_of ? configuration_of() : nullptr;
  if (!configuration)
    fail(fmt::format(
        "not an rkhs-study plugin (it has plugin ABI {} but exports no "
        "rkhs_plugin_build_configuration; declare the module with RKHS_PLUGIN_MODULE(name))",
        abi));
  const BuildConfiguration framework = framework_build_configuration();
  if (!(*configuration == framework))
    fail(fmt::format(
        "built for {}, this rkhs-study is built for {} ({}); build the plugin with the same "
        "compiler and flags as rkhs-study (its CMake package's rkhs_study::plugin carries the "
        "sanitizer flags; do not add -march, -mavx or EIGEN_* alignment options)",
        describe(*configuration), describe(framework),
        describe_difference(*configuration, framework)));
  if (!RegistryState::take().same(before))
    fail(
        "registered plugins while being loaded, before its ABI could be checked: compile every "
        "source of the module with RKHS_BUILDING_PLUGIN defined (rkhs_study_add_plugin() and "
        "rkhs_study::plugin do)");

  auto* name_of = symbol<const char*() noexcept>(handle, "rkhs_plugin_name");
  auto* register_all = symbol<int() noexcept>(handle, "rkhs_plugin_register");
  if (!name_of || !register_all)
    fail(
        "not an rkhs-study plugin (it exports rkhs_plugin_abi_version but not rkhs_plugin_name "
        "and rkhs_plugin_register; declare the module with RKHS_PLUGIN_MODULE(name))");
  const std::string name = name_of() ? name_of() : "";
  if (name.empty()) fail("invalid plugin metadata: empty module name in RKHS_PLUGIN_MODULE");
  for (const auto& module : modules())
    if (module.plugin.name == name)
      fail(fmt::format("duplicate plugin name '{}' (already loaded from {})", name,
                       module.plugin.file.string()));

  const int failed = register_all();
  const auto after = RegistryState::take();
  if (!after.same_errors(before)) {
    const auto errors = roll_back(before);
    dlclose(handle);
    throw PluginError(fmt::format("{}: {}", shown, fmt::join(errors, "; ")));
  }
  if (failed < 0)
    fail(fmt::format("registers more than {} plugins in one module",
                     plugin_detail::PendingRegistrations::capacity));
  if (failed > 0)
    fail(
        fmt::format("{} registration(s) failed without a recorded reason (out of memory while "
                    "recording it)",
                    failed));

  LoadedPlugin plugin;
  plugin.file = canonical;
  plugin.sha256 = content_hash;
  plugin.name = name;
  plugin.rkhs_study_version = built_with;
  plugin.abi_version = abi;
  plugin.build_configuration = describe(*configuration);
  bool registered = false;
  for_each_plugin_kind([&](auto kind) {
    using Kind = decltype(kind);
    const std::string key(Kind::singular);
    auto names = added(before.names.at(key), after.names.at(key));
    registered = registered || !names.empty();
    plugin.registered[key] = std::move(names);
  });
  if (!registered) {
    // The registration macros, RKHS_REGISTER_<KIND>, named from the table of plugin kinds.
    std::vector<std::string> macros;
    for_each_plugin_kind([&](auto kind) {
      std::string suffix(decltype(kind)::singular);
      for (auto& c : suffix) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
      macros.push_back(macros.empty() ? "RKHS_REGISTER_" + suffix + "(Type)" : "_" + suffix);
    });
    fail(fmt::format("registered nothing (use {}, or {}, in the module's sources)", macros.front(),
                     fmt::join(macros.begin() + 1, macros.end(), ", ")));
  }
  modules().push_back({plugin, handle});
  return plugin;
}

std::vector<LoadedPlugin> loaded_plugins() {
  std::lock_guard lock(loader_mutex());
  std::vector<LoadedPlugin> out;
  for (const auto& module : modules()) out.push_back(module.plugin);
  return out;
}

bool unload_plugin(const fs::path& file) {
  std::lock_guard lock(loader_mutex());
  std::error_code error;
  const fs::path canonical = fs::canonical(file, error);
  auto& loaded = modules();
  const auto it = std::find_if(loaded.begin(), loaded.end(),
                               [&](const Module& m) { return m.plugin.file == canonical; });
  if (error || it == loaded.end() || it->handle == nullptr) return false;
  remove_all(it->plugin.registered);
  dlclose(it->handle);
  loaded.erase(it);
  return true;
}

void record_host_plugins(LoadedPlugin plugin) {
  std::lock_guard lock(loader_mutex());
  auto& loaded = modules();
  const auto it = std::find_if(loaded.begin(), loaded.end(), [&](const Module& m) {
    return m.handle == nullptr && m.plugin.file == plugin.file;
  });
  if (it != loaded.end())
    it->plugin = std::move(plugin);
  else
    loaded.push_back({std::move(plugin), nullptr});
}

bool forget_host_plugins(const fs::path& file) {
  std::lock_guard lock(loader_mutex());
  auto& loaded = modules();
  const auto it = std::find_if(loaded.begin(), loaded.end(), [&](const Module& m) {
    return m.handle == nullptr && m.plugin.file == file;
  });
  if (it == loaded.end()) return false;
  remove_all(it->plugin.registered);
  loaded.erase(it);
  return true;
}

std::vector<fs::path> plugin_path_files(std::string_view value) {
  std::vector<fs::path> files;
  while (true) {
    const auto colon = value.find(':');
    const std::string entry(value.substr(0, colon));
    if (!entry.empty()) {
      std::error_code error;
      if (fs::is_directory(entry, error)) {
        std::vector<fs::path> found;
        for (const auto& item : fs::directory_iterator(entry, error))
          if (item.path().extension() == ".so" && !item.is_directory())
            found.push_back(item.path());
        std::sort(found.begin(), found.end());
        files.insert(files.end(), found.begin(), found.end());
      } else if (fs::exists(entry, error)) {
        files.emplace_back(entry);
      } else {
        throw PluginError(entry + ": no such plugin file or directory");
      }
    }
    if (colon == std::string_view::npos) break;
    value.remove_prefix(colon + 1);
  }
  return files;
}

void load_plugins_from_environment() {
  const char* value = std::getenv("RKHS_STUDY_PLUGIN_PATH");
  if (!value) return;
  try {
    for (const auto& file : plugin_path_files(value)) load_plugin(file);
  } catch (const PluginError& e) {
    throw PluginError(std::string("RKHS_STUDY_PLUGIN_PATH: ") + e.what());
  }
}

}  // namespace rkhs
