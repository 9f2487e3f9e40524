// `import mesolab`: the Python face of mesolab's core (python/README.md). Everything here calls
// what the command line calls, so a frame rendered through Python equals `mesolab capture` of the
// same scene and settings, and an error carries the same words as the CLI's.
//
// [SECTION] index
//   Errors          InputError (a ValueError), MemoryBudgetError (an InputError), Cancelled
//   Worker          long work on a thread of its own; the caller's thread polls for Ctrl-C
//   Values          Python values <-> parameter values (the --set text, typed values back)
//   Scene           presets: load, set/get keys (object=), JSON, atomic save
//   Frame           a rendered frame: numpy views of its AOVs, stages, timings, save, PNG
//   Workbench       one session (stage cache, memory budget, GL context) on one worker thread
//   Module          __version__, info, schema, load_preset, bench, sweep, frontier
//   Cluster layer   packs and partial truths as bytes, for python/mesolab/cluster.py (names with a leading _)
// The package mesolab (python/mesolab/__init__.py) re-exports these and adds client= (cluster.py).
#include "app/api.h"
#include "app/workbench.h"
#include "core/error.h"
#include "core/image.h"
#include "core/pack.h"
#include "core/scene.h"
#include "core/session.h"
#include "core/stage_store.h"
#include "core/strings.h"
#include "core/technique.h"
#include "core/renderer.h"
#include "core/truth/cache.h"
#include "gpu/headless.h"
#include "core/truth/truth.h"
#include "core/stage_store.h"

#include <OpenImageIO/imageio.h>
#include <tbb/global_control.h>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>
#include <unistd.h>

namespace py = pybind11;
namespace fs = std::filesystem;
using namespace mesolab;

namespace {

// [SECTION] Values
// A path argument: str or os.PathLike.
std::string path_arg(const py::object& p) { return py::str(py::module_::import("os").attr("fspath")(p)).cast<std::string>(); }

py::object from_json(const json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

// A Python value as `--set` text, so that Python and the command line check it alike.
std::string to_set_text(const std::string& key, const py::handle& h) {
    const auto v = py::reinterpret_borrow<py::object>(h);
    if (py::isinstance<py::bool_>(v)) return v.cast<bool>() ? "true" : "false";
    if (py::isinstance<py::str>(v)) return v.cast<std::string>();
    if (py::hasattr(v, "__fspath__")) return py::str(py::module_::import("os").attr("fspath")(v)).cast<std::string>();
    const py::module_ np = py::module_::import("numpy");
    if (py::isinstance(v, np.attr("bool_"))) return v.cast<bool>() ? "true" : "false";
    if (py::isinstance<py::int_>(v) || py::isinstance(v, np.attr("integer"))) return py::str(py::int_(v)).cast<std::string>();
    if (py::isinstance<py::float_>(v) || py::isinstance(v, np.attr("floating"))) return py::repr(py::float_(v)).cast<std::string>();
    if (py::isinstance<py::sequence>(v) || py::isinstance(v, np.attr("ndarray"))) {
        std::string r;
        for (const py::handle& e : py::iter(v)) {
            if (!(py::isinstance<py::int_>(e) || py::isinstance<py::float_>(e) || py::isinstance(e, np.attr("number"))) || py::isinstance<py::bool_>(e))
                throw InputError(key + ": expected numbers in the sequence, got " + py::repr(e).cast<std::string>());
            r += (r.empty() ? "" : ",") + to_set_text(key, e);
        }
        return r;
    }
    throw InputError(key + ": expected a bool, a number, a string or a sequence of numbers, got " + py::repr(v).cast<std::string>());
}

py::object to_python(const Value& v) {
    return std::visit(
        [](const auto& x) -> py::object {
            using T = std::decay_t<decltype(x)>;
            if constexpr (std::is_same_v<T, std::array<double, 2>>) return py::make_tuple(x[0], x[1]);
            else if constexpr (std::is_same_v<T, std::array<double, 3>>) return py::make_tuple(x[0], x[1], x[2]);
            else return py::cast(x);
        },
        v);
}

// [SECTION] Arrays as image files
// An image given as a numpy array is written once, under a name made from its contents, into
// $MESOLAB_CACHE_DIR/arrays (else $XDG_CACHE_HOME/mesolab/arrays, else ~/.cache/mesolab/arrays),
// and the key names that file. The loaders then read it as they read any file, and the stage
// cache keys follow the contents: the same array again reuses the stages, another recomputes.
// float arrays become float EXR (linear values, as an EXR holds); uint8 and uint16 arrays PNG
// (what an 8/16-bit file means, e.g. sRGB for albedo maps).
// The folder is never evicted: presets name its files.
std::string arrays_folder() {
    const std::string folder = cache_folder("arrays");
    if (folder.empty()) throw std::runtime_error("no folder for arrays given as images: set MESOLAB_CACHE_DIR (or HOME)");
    return folder;
}

std::string store_array(const std::string& key, const py::array& given) {
    if (given.ndim() != 2 && given.ndim() != 3)
        throw InputError(key + ": expected an image array of shape (H, W) or (H, W, C), got " + std::to_string(given.ndim()) + " dimensions");
    const char kind = given.dtype().kind();
    const size_t item = size_t(given.dtype().itemsize());
    OIIO::TypeDesc type;
    py::array a;
    if (kind == 'f') {
        a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(given);
        type = OIIO::TypeDesc::FLOAT;
        const py::module_ np = py::module_::import("numpy");
        if (!np.attr("isfinite")(a).attr("all")().cast<bool>()) throw InputError(key + ": the array holds non-finite values (NaN or infinity)");
    } else if (kind == 'u' && item == 1) {
        a = py::array_t<uint8_t, py::array::c_style | py::array::forcecast>::ensure(given);
        type = OIIO::TypeDesc::UINT8;
    } else if (kind == 'u' && item == 2) {
        a = py::array_t<uint16_t, py::array::c_style | py::array::forcecast>::ensure(given);
        type = OIIO::TypeDesc::UINT16;
    } else {
        throw InputError(key + ": expected a float, uint8 or uint16 image array, got dtype " + py::str(given.dtype()).cast<std::string>());
    }
    const int h = int(a.shape(0)), w = int(a.shape(1)), c = a.ndim() == 3 ? int(a.shape(2)) : 1;
    if (w < 1 || h < 1 || c < 1 || c > 4) throw InputError(key + ": expected an image of 1 to 4 channels and at least 1x1 pixels, got shape " + py::str(py::tuple(given.attr("shape"))).cast<std::string>());
    const size_t bytes = size_t(w) * size_t(h) * size_t(c) * type.size();
    const std::string header = strprintf("%dx%dx%d %s;", w, h, c, type.c_str());
    std::string content = header;
    content.append(static_cast<const char*>(a.data()), bytes);
    const std::string name = strprintf("%016llx-%dx%dx%d", static_cast<unsigned long long>(StageGraph::hash(content)), w, h, c) +
                             (type == OIIO::TypeDesc::FLOAT ? ".exr" : ".png");
    const fs::path folder = arrays_folder(), path = folder / name;
    std::error_code ec;
    if (fs::is_regular_file(path, ec)) return path.string();
    // Written beside its final name, then renamed (core/file.h): a reader never sees half a file.
    try {
        if (type == OIIO::TypeDesc::FLOAT) {
            Image img;
            img.width = w, img.height = h, img.channels = c;
            const float* px = static_cast<const float*>(a.data());
            img.data.assign(px, px + size_t(w) * size_t(h) * size_t(c));
            write_exr(path.string(), img);
        } else {
            write_png_raw(path.string(), w, h, c, type == OIIO::TypeDesc::UINT8 ? 8 : 16, a.data());
        }
    } catch (const InputError& e) {
        throw InputError(key + ": could not store the array: " + e.what());
    }
    return path.string();
}

// "basic.kd" for one object (index or name): objects.N.material.kd; "geometry.X": objects.N.geometry.X.
std::string object_key(const Scene& s, const std::string& key, const py::object& object) {
    if (object.is_none()) return key;
    int index = -1;
    if (py::isinstance<py::str>(object)) {
        const std::string name = object.cast<std::string>();
        std::vector<std::string> names;
        for (size_t i = 0; i < s.objects.size(); ++i) {
            if (s.objects[i].name == name) index = int(i);
            names.push_back(s.objects[i].name);
        }
        if (index < 0) throw InputError(key + ": object '" + name + "' is not in the scene; its objects are: " + join(names, ", "));
    } else if (py::isinstance<py::int_>(object)) {
        index = object.cast<int>();
        if (index < 0 || size_t(index) >= s.objects.size())
            throw InputError(key + ": object " + std::to_string(index) + " is out of range (the scene has " + std::to_string(s.objects.size()) + " objects)");
    } else {
        throw InputError(key + ": object= takes an index or a name, got " + py::repr(object).cast<std::string>());
    }
    const auto dot = key.find('.');
    const std::string group = key.substr(0, dot), param = dot == std::string::npos ? "" : key.substr(dot + 1);
    if (dot == std::string::npos || param.find('.') != std::string::npos || param.empty())
        throw InputError(key + ": object= applies to geometry.* and TECHNIQUE.* keys (e.g. basic.kd)");
    const SceneObject& o = s.objects[size_t(index)];
    if (group == "geometry") return "objects." + std::to_string(index) + ".geometry." + param;
    if (!Registry::instance().technique(group)) throw InputError(key + ": object= applies to geometry.* and TECHNIQUE.* keys (e.g. basic.kd)");
    if (o.technique != group)
        throw InputError(key + ": object " + std::to_string(index) + " ('" + o.name + "') uses technique '" + o.technique + "', not '" + group + "'");
    return "objects." + std::to_string(index) + ".material." + param;
}

// spp=, noise=, time_limit= (seconds) of a truth, checked with their Python names: spp None is 64,
// or unlimited with a noise target or a time limit.
// The truth's sampling from Python's arguments (None: not given), checked by core's truth_sampling
// with the Python names.
TruthSettings truth_sampling_arg(const py::object& spp, const py::object& noise, const py::object& time_limit, uint64_t seed) {
    return truth_sampling(spp.is_none() ? std::nullopt : std::optional<int>(spp.cast<int>()), noise.is_none() ? 0.0 : noise.cast<double>(),
                          time_limit.is_none() ? 0.0 : time_limit.cast<double>(), seed, {"spp=", "noise=", "time_limit=", "samples="});
}

std::pair<int, int> frame_size_arg(const py::object& size) {
    std::optional<std::pair<int, int>> given;
    if (py::isinstance<py::str>(size)) {
        given = parse_wxh(size.cast<std::string>());
        if (!given) throw InputError("size: expected (width, height) or 'WxH' (e.g. '512x512'), got '" + size.cast<std::string>() + "'");
    }
    try {
        const auto t = given ? *given : size.cast<std::pair<int, int>>();
        if (t.first < 1 || t.second < 1 || t.first > 16384 || t.second > 16384)
            throw InputError("size: (" + std::to_string(t.first) + ", " + std::to_string(t.second) + ") is out of range (1..16384 per side)");
        return t;
    } catch (const py::cast_error&) {
        throw InputError("size: expected (width, height) or 'WxH', got " + py::repr(size).cast<std::string>());
    }
}

uint64_t memory_limit_arg(const py::object& limit) {
    if (limit.is_none()) return 0;
    if (py::isinstance<py::int_>(limit)) {
        const long long b = limit.cast<long long>();
        if (b <= 0) throw InputError("memory_limit: " + std::to_string(b) + " bytes; expected a positive size");
        return uint64_t(b);
    }
    return parse_memory_size(limit.cast<std::string>());
}

// [SECTION] Worker
// A thread that runs one task after another. A Workbench owns one: its GL context is current on
// that thread only, and every call for it runs there.
class Worker {
public:
    Worker() : thread_([this] { loop(); }) {}
    ~Worker() {
        {
            std::lock_guard lock(mutex_);
            stop_ = true;
        }
        cv_.notify_all();
        thread_.join();
    }
    void post(std::function<void()> task) {
        {
            std::lock_guard lock(mutex_);
            tasks_.push_back(std::move(task));
        }
        cv_.notify_all();
    }

private:
    void loop() {
        for (;;) {
            std::function<void()> task;
            {
                std::unique_lock lock(mutex_);
                cv_.wait(lock, [&] { return stop_ || !tasks_.empty(); });
                if (tasks_.empty()) return;
                task = std::move(tasks_.front());
                tasks_.pop_front();
            }
            task();
        }
    }
    std::mutex mutex_;
    std::condition_variable cv_;
    std::deque<std::function<void()>> tasks_;
    bool stop_ = false;
    std::thread thread_;  // last: starts once the rest exists
};

// The latest progress report of a task, handed from its thread to the caller's.
struct Progress {
    std::mutex mutex;
    std::string stage;
    double fraction = 0;
    bool fresh = false;
    ProgressFn fn() {
        return [this](const std::string& s, double f) {
            std::lock_guard lock(mutex);
            stage = s, fraction = f, fresh = true;
        };
    }
};

// Runs work(progress, cancel) on `worker` while this thread, without the GIL, waits for it and
// every 50 ms takes the GIL to pass on progress and to check for signals. Ctrl-C (or a progress
// callback that raises) sets the cancel flag; the work stops at its next check, and the exception
// is raised here once it has. The task never outlives this call.
// `poll` (optional) is called the same way every 50 ms, progress or not: it stops the work by raising.
template <class R>
R run_on(Worker& worker, const py::object& progress_cb, const std::function<R(const ProgressFn&, const std::atomic<bool>*)>& work,
         const py::object& poll = py::none()) {
    Progress progress;
    std::atomic<bool> cancel{false};
    std::promise<R> promise;
    std::future<R> result = promise.get_future();
    const ProgressFn fn = progress.fn();
    worker.post([&] {
        try {
            promise.set_value(work(progress_cb.is_none() ? ProgressFn{} : fn, &cancel));
        } catch (...) {
            promise.set_exception(std::current_exception());
        }
    });
    const auto stop_and_wait = [&] {
        cancel = true;
        py::gil_scoped_release nogil;
        result.wait();
    };
    for (;;) {
        bool ready = false;
        {
            py::gil_scoped_release nogil;
            ready = result.wait_for(std::chrono::milliseconds(50)) == std::future_status::ready;
        }
        if (!progress_cb.is_none()) {
            std::string stage;
            double fraction = 0;
            bool fresh = false;
            {
                std::lock_guard lock(progress.mutex);
                std::swap(fresh, progress.fresh);
                stage = progress.stage, fraction = progress.fraction;
            }
            if (fresh) {
                try {
                    progress_cb(stage, fraction);
                } catch (...) {
                    stop_and_wait();
                    throw;
                }
            }
        }
        if (ready) break;
        if (!poll.is_none()) {
            try {
                poll();
            } catch (...) {
                stop_and_wait();
                throw;
            }
        }
        if (PyErr_CheckSignals() != 0) {
            py::error_already_set interrupted;  // takes the pending KeyboardInterrupt
            stop_and_wait();
            throw interrupted;
        }
    }
    return result.get();
}

// Work on a worker of its own (module functions: bench and sweep make their own session).
template <class R>
R run_alone(const py::object& progress_cb, const std::function<R(const ProgressFn&, const std::atomic<bool>*)>& work) {
    Worker worker;
    return run_on<R>(worker, progress_cb, work);
}

// [SECTION] Scene
struct PyScene {
    Scene scene;
    std::vector<std::string> set_keys;  // keys set since loading: each must be used when rendered (as --set)

    void set(const std::string& key, const py::object& value, const py::object& object) {
        const std::string k = object_key(scene, key, object);
        // An image as an array, for a key that names a file: stored by its contents (store_array).
        if (py::isinstance<py::array>(value) && py::array(value).ndim() >= 2 && decl_of(scene, k).type == ParamType::Path)
            apply_set(scene, k, store_array(k, value));
        else
            apply_set(scene, k, to_set_text(k, value));
        if (std::find(set_keys.begin(), set_keys.end(), k) == set_keys.end()) set_keys.push_back(k);
    }
    py::object get(const std::string& key, const py::object& object) const { return to_python(get_public_value(scene, object_key(scene, key, object))); }
    // What --set checks once every setting is made: a key the final settings do not use.
    void check_used() const {
        for (const auto& k : set_keys) check_set_used(scene, k);
    }
};

// [SECTION] Frame
struct PyFrame {
    std::shared_ptr<const RenderResult> r;
    Scene scene;
    TruthSettings truth;

    const Image& image(const std::string& name) const {
        if (!r->frame.has(name)) {
            std::vector<std::string> names;
            for (const auto& a : r->frame.layout) names.push_back(a.name);
            throw py::key_error("frame has no AOV '" + name + "'; it holds " + join(names, ", ") + " (ask for more with aovs=[...])");
        }
        return r->frame.aov(name);
    }
    // A read-only (H, W, C) float32 view that keeps the frame's data alive.
    py::array array(const std::string& name) const {
        const Image& img = image(name);
        auto* keep = new std::shared_ptr<const RenderResult>(r);
        py::capsule owner(keep, [](void* p) { delete static_cast<std::shared_ptr<const RenderResult>*>(p); });
        const auto c = py::ssize_t(img.channels), w = py::ssize_t(img.width);
        py::array a(py::dtype::of<float>(), {py::ssize_t(img.height), w, c},
                    {py::ssize_t(sizeof(float)) * w * c, py::ssize_t(sizeof(float)) * c, py::ssize_t(sizeof(float))}, img.data.data(), owner);
        a.attr("setflags")(py::arg("write") = false);
        return a;
    }
    std::vector<std::string> aov_names() const {
        std::vector<std::string> names;
        for (const auto& a : r->frame.layout) names.push_back(a.name);
        return names;
    }
    json sidecar(const std::vector<std::string>& written = {}) const { return capture_sidecar(scene, "", *r, written, truth); }
    py::list save(const py::object& where) const {
        const std::string dir = path_arg(where);
        std::error_code ec;
        fs::create_directories(dir, ec);
        if (ec) throw InputError(dir + ": could not create the folder (" + ec.message() + ")");
        std::vector<std::string> names;
        for (const auto& a : r->frame.layout) names.push_back(a.name);
        const std::vector<std::string> aovs = rendered_aovs(names);  // a comparison AOV is written as its pictures (write_capture)
        py::list out;
        for (const auto& p : write_capture(dir, scene, "", *r, aovs, truth)) out.append(p);
        return out;
    }
    py::bytes png() const {
        char name[] = "/tmp/mesolab-frame-XXXXXX.png";
        const int fd = ::mkstemps(name, 4);
        if (fd < 0) throw std::runtime_error("could not create a temporary file for the frame's PNG");
        ::close(fd);
        std::string bytes;
        try {
            write_png_srgb(name, r->frame.aov("radiance"));
            std::ifstream f(name, std::ios::binary);
            bytes.assign(std::istreambuf_iterator<char>(f), {});
        } catch (...) {
            std::remove(name);
            throw;
        }
        std::remove(name);
        return py::bytes(bytes);
    }
    std::string repr() const {
        return strprintf("<mesolab.Frame %dx%d %s of '%s': %s; stages %.1f ms, render %.1f ms>", r->frame.width, r->frame.height, r->renderer.c_str(),
                         scene.name.c_str(), join(aov_names(), ", ").c_str(), r->stages_ms, r->render_ms);
    }
};

// [SECTION] Frontier values
// A frontier's options from the keyword arguments of frontier() (and its cluster layer's parts).
FrontierOptions frontier_options(const py::object& size, const std::string& backend, const std::vector<double>& distances, const py::object& spp,
                                 uint64_t seed, const py::object& noise, const py::object& time_limit, double budget, int repeat,
                                 const py::object& memory_limit) {
    const auto [w, h] = frame_size_arg(size);
    FrontierOptions o;
    o.width = w, o.height = h;
    o.backend = RendererRegistry::instance().find(backend, "backend=").name;
    o.distances = distances;
    o.truth = truth_sampling_arg(spp, noise, time_limit, seed);
    if (!(budget >= 0.0)) throw InputError("budget=" + strprintf("%g", budget) + ": expected seconds, 0 or more");
    o.budget_s = budget, o.repeat = repeat, o.quiet = true;
    o.memory_limit = memory_limit_arg(memory_limit);
    return o;
}

// The same from a dict of those names (the cluster layer's tasks); an unknown name is an error.
FrontierOptions frontier_options(const py::dict& d) {
    static const std::vector<std::string> names = {"size", "backend", "distances", "spp", "seed", "budget", "repeat", "memory_limit"};
    for (const auto& [k, v] : d)
        if (std::find(names.begin(), names.end(), k.cast<std::string>()) == names.end())
            throw InputError("frontier options: unknown '" + k.cast<std::string>() + "' (known: " + join(names, ", ") + ")");
    const auto get = [&](const char* k, py::object dflt) { return d.contains(k) ? py::reinterpret_borrow<py::object>(d[k]) : dflt; };
    return frontier_options(get("size", py::make_tuple(128, 128)), get("backend", py::str("cpu")).cast<std::string>(),
                            get("distances", py::list()).cast<std::vector<double>>(), get("spp", py::none()), get("seed", py::int_(1)).cast<uint64_t>(),
                            py::none(), py::none(), get("budget", py::float_(600.0)).cast<double>(), get("repeat", py::int_(3)).cast<int>(),
                            get("memory_limit", py::none()));
}

// {distance, method, setting, knobs: {KEY: VALUE in order}, frame_ms, precompute_ms, rmse_rel, below_noise, on_frontier}
py::dict frontier_point_dict(const FrontierPoint& p) {
    py::dict d, knobs;
    for (const auto& [k, v] : p.settings) knobs[py::str(k)] = v;
    d["distance"] = p.distance, d["method"] = p.method, d["setting"] = p.varied, d["knobs"] = knobs;
    d["frame_ms"] = p.frame_ms, d["precompute_ms"] = p.precompute_ms, d["rmse_rel"] = p.rmse_rel;
    d["below_noise"] = p.below_noise, d["on_frontier"] = p.on_frontier;
    return d;
}

py::object dict_item(const py::dict& d, const char* key, const char* what) {
    if (!d.contains(key)) throw InputError(std::string(what) + ": no '" + key + "'");
    return d[key];
}

std::vector<std::pair<std::string, std::string>> knobs_of_dict(const py::dict& d, const char* what) {
    std::vector<std::pair<std::string, std::string>> r;
    for (const auto& [k, v] : dict_item(d, "knobs", what).cast<py::dict>()) r.emplace_back(k.cast<std::string>(), v.cast<std::string>());
    return r;
}

FrontierPoint frontier_point_of(const py::dict& d) {
    FrontierPoint p;
    p.distance = dict_item(d, "distance", "frontier point").cast<double>();
    p.method = dict_item(d, "method", "frontier point").cast<std::string>();
    p.varied = dict_item(d, "setting", "frontier point").cast<std::string>();
    p.settings = knobs_of_dict(d, "frontier point");
    p.frame_ms = dict_item(d, "frame_ms", "frontier point").cast<double>();
    p.precompute_ms = dict_item(d, "precompute_ms", "frontier point").cast<double>();
    p.rmse_rel = dict_item(d, "rmse_rel", "frontier point").cast<double>();
    p.below_noise = dict_item(d, "below_noise", "frontier point").cast<bool>();
    return p;
}

// {method, setting, knobs: {KEY: VALUE in order}}: a setting as a point names it.
py::dict frontier_setting_dict(const FrontierSetting& st) {
    py::dict d, knobs;
    for (const auto& [k, v] : st.settings) knobs[py::str(k)] = v;
    d["method"] = st.method, d["setting"] = st.varied, d["knobs"] = knobs;
    return d;
}

FrontierSetting frontier_setting_of(const py::dict& d) {
    return {dict_item(d, "method", "frontier setting").cast<std::string>(), dict_item(d, "setting", "frontier setting").cast<std::string>(),
            knobs_of_dict(d, "frontier setting")};
}

// [SECTION] Workbench
class PyWorkbench {
public:
    explicit PyWorkbench(const py::object& memory_limit) : limit_(memory_limit_arg(memory_limit)) {
        run_on<int>(worker_, py::none(), [this](const ProgressFn&, const std::atomic<bool>*) {
            wb_ = std::make_unique<Workbench>();
            wb_->session().set_memory_limit(limit_);
            store_ = StageStore::from_environment(version_string());
            wb_->session().set_store(store_);  // expensive stages kept between runs
            return 0;
        });
    }
    ~PyWorkbench() { close(); }

    // Frees the session's caches and its GL context now (not when Python collects the object).
    void close() {
        // GL objects and the context go on the thread they were made on.
        py::gil_scoped_release nogil;
        std::promise<void> done;
        worker_.post([&] {
            wb_.reset();
            done.set_value();
        });
        done.get_future().wait();
    }
    Workbench& open() const {
        if (!wb_) throw InputError("Workbench: closed; make a new one");
        return *wb_;
    }

    PyFrame render(const PyScene& ps, const py::object& size, const std::string& backend, const std::vector<std::string>& aovs, const py::object& spp,
                   uint64_t seed, const py::object& noise, const py::object& time_limit, const py::object& progress) {
        open();
        ps.check_used();
        const auto [w, h] = frame_size_arg(size);
        RenderRequest req;
        req.renderer = RendererRegistry::instance().find(backend, "backend=").name;
        req.width = w, req.height = h;
        req.aovs = aovs.empty() ? std::vector<std::string>{"radiance"} : aovs;
        req.truth = truth_sampling_arg(spp, noise, time_limit, seed);
        PyFrame f{nullptr, ps.scene, req.truth};
        f.r = run_on<std::shared_ptr<const RenderResult>>(worker_, progress, [&](const ProgressFn& p, const std::atomic<bool>* cancel) {
            RenderRequest rq = req;
            rq.progress = p;
            rq.cancel = cancel;
            return std::make_shared<const RenderResult>(open().render(ps.scene, rq));
        });
        return f;
    }

    // [SECTION] Truths in parts (the cluster layer, mesolab/cluster.py)
    // Samples [first, end) of the truth of `ps` as a partial truth's bytes (truth_part_bytes:
    // `capture --samples A:B`'s file), neither read from nor kept in the truth cache.
    py::bytes truth_part(const PyScene& ps, const py::object& size, uint64_t seed, int first, int end, const py::object& progress) {
        open();
        ps.check_used();
        const auto [w, h] = frame_size_arg(size);
        RenderRequest req;
        req.renderer = "truth";
        req.width = w, req.height = h;
        req.aovs = {"radiance"};
        req.truth.seed = seed;
        req.truth.first = first;
        req.truth.spp = end;
        req.partial = true;
        check_truth_settings(req.truth, TruthOptionNames{"spp=", "noise=", "time_limit=", "samples="});
        const std::string bytes = run_on<std::string>(worker_, progress, [&](const ProgressFn& p, const std::atomic<bool>* cancel) {
            RenderRequest rq = req;
            rq.progress = p;
            rq.cancel = cancel;
            const RenderResult r = open().render(ps.scene, rq);
            return truth_part_bytes(TruthPart{ps.scene.name, r.sampled->key, truth_build(version_string()), *r.sampled->sums});
        });
        return py::bytes(bytes);
    }
    // The frame of a merged truth of `ps` (samples from 0), as render(backend="truth") gives it,
    // and kept in the truth cache as if rendered here. InputError when it is another scene's truth
    // (another key: scene, size or seed) or another build's.
    // noise, time_limit: the targets it was sampled to (the sidecar's), `ended`: what ended it (samples, noise, time limit).
    PyFrame truth_from_part(const PyScene& ps, const py::bytes& part_bytes, const py::object& progress, double noise, double time_limit,
                            const std::string& ended) {
        open();
        ps.check_used();
        const TruthPart part = truth_part_from_bytes(std::string(part_bytes), "the merged truth");
        const TruthAccumulator& a = part.sums;
        if (a.first != 0) throw InputError("the merged truth starts at sample " + std::to_string(a.first) + ", not 0: a part is missing");
        const std::string here = truth_build(version_string());
        if (part.build != here)
            throw InputError("the truth's samples were made by another build (" + part.build + "; here: " + here +
                             "): its bits differ from this build's; not used");
        TruthSettings ts;
        ts.spp = a.spp;
        ts.seed = a.seed;
        ts.noise = noise, ts.time_limit_s = time_limit;
        TruthEnd end = TruthEnd::Samples;
        if (ended == "noise") end = TruthEnd::Noise;
        else if (ended == "time limit") end = TruthEnd::TimeLimit;
        else if (ended != "samples") throw InputError("ended=" + ended + ": expected samples, noise or time limit");
        PyFrame f{nullptr, ps.scene, ts};
        f.r = run_on<std::shared_ptr<const RenderResult>>(worker_, progress, [&](const ProgressFn& p, const std::atomic<bool>* cancel) {
            auto r = std::make_shared<RenderResult>();
            const auto t0 = std::chrono::steady_clock::now();
            r->eval = open().session().evaluate(ps.scene, truth_stages(ps.scene), p, cancel);
            r->stages_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
            const std::string key = truth_cache_key(version_string(), ps.scene, a.width, a.height, a.seed);
            if (key != part.key) throw InputError("the merged truth is not of this scene at this size and seed (its key " + part.key + ", this scene's " + key + ")");
            r->frame = truth_frame(a);
            r->renderer = "truth";
            SampledRun run;
            run.spp = a.samples();
            run.cached_spp = a.spp;
            run.ended = end;
            run.key = key;
            r->sampled = run;
            TruthCache(cache_folder("truth"), version_string()).store(key, a);  // a later render(backend="truth") reads it
            return std::shared_ptr<const RenderResult>(std::move(r));
        });
        return f;
    }

    std::string gl_renderer() {
        return run_on<std::string>(worker_, py::none(), [this](const ProgressFn&, const std::atomic<bool>*) { return open().gl_renderer(); });
    }
    void clear_cache() {
        run_on<int>(worker_, py::none(), [this](const ProgressFn&, const std::atomic<bool>*) {
            open().session().cache().clear();
            open().forget_frame_steps();
            return 0;
        });
    }
    size_t cache_entries() {
        return run_on<size_t>(worker_, py::none(), [this](const ProgressFn&, const std::atomic<bool>*) { return open().session().cache().entries(); });
    }
    uint64_t memory_limit() const { return limit_; }

    // [SECTION] A frontier's point (the cluster layer): one setting at one distance on this
    // workbench (frontier_measure), its stage store set aside meanwhile (the precomputation is timed
    // from a cold cache), its truth from the truth cache. `poll` as run_on's.
    // Work on this workbench's thread with its stage store set aside (the work times from a cold
    // cache) and, when not 0, `memory_limit` set, both as they were afterwards. For the cluster
    // layer's tasks, which share one workbench per worker process. `poll` as run_on's.
    template <class R>
    R borrow(const py::object& progress, uint64_t memory_limit, const std::function<R(Workbench&, const ProgressFn&, const std::atomic<bool>*)>& work,
             const py::object& poll = py::none()) {
        open();
        return run_on<R>(
            worker_, progress,
            [&](const ProgressFn& p, const std::atomic<bool>* cancel) {
                Workbench& wb = open();
                struct Restore {
                    Workbench& wb;
                    std::shared_ptr<const StageStore> store;
                    uint64_t limit;
                    ~Restore() {
                        wb.session().set_store(store);
                        wb.session().set_memory_limit(limit);
                    }
                } restore{wb, store_, wb.session().memory_limit()};
                wb.session().set_store(nullptr);
                if (memory_limit) wb.session().set_memory_limit(memory_limit);
                return work(wb, p, cancel);
            },
            poll);
    }

    // [SECTION] A frontier's point (the cluster layer): one setting at one distance on this
    // workbench (frontier_measure), its truth from the truth cache.
    py::dict frontier_point(const PyScene& ps, const FrontierOptions& o, double distance, const FrontierSetting& setting, const py::object& poll) {
        open();
        ps.check_used();
        // poll() returning true: the budget has ended (a setting not yet measured stops, as frontier_measure's budget_over).
        auto budget = std::make_shared<std::atomic<bool>>(false);
        const py::object polled = poll.is_none() ? py::object(py::none()) : py::object(py::cpp_function([poll, budget] {
            if (py::bool_(poll())) *budget = true;
        }));
        if (!polled.is_none()) polled();  // a setting that starts after the budget ended does not start
        const FrontierMeasurement m = borrow<FrontierMeasurement>(
            py::none(), o.memory_limit,
            [&](Workbench& wb, const ProgressFn&, const std::atomic<bool>* cancel) {
                FrontierOptions run = o;
                run.cancel = cancel;
                // The truths met so far, kept for the next points of a frontier with these truth settings (as one process keeps
                // them for its run): read from the truth cache each time, a truth's own stages would be evaluated again per point.
                const TruthSettings& t = o.truth;
                const std::string settings = strprintf("%d/%llu/%d/%.17g/%.17g", t.spp, (unsigned long long)t.seed, t.max_depth, t.noise, t.time_limit_s);
                if (settings != truths_for_ || truths_.frames.size() > 16) truths_ = {}, truths_for_ = settings;
                return frontier_measure(wb, ps.scene, run, distance, setting, truths_, [budget] { return budget->load(); });
            },
            polled);
        py::dict d;
        d["point"] = m.point ? frontier_point_dict(*m.point) : py::object(py::none());
        d["skipped"] = m.skipped;
        d["stopped"] = m.stopped;
        d["truth_noise"] = m.truth_noise;
        d["machine"] = cpu_model() + ", " + std::to_string(std::thread::hardware_concurrency()) + " threads" +
                       (RendererRegistry::instance().find(o.backend).traits.needs_gl ? "; GL: " + gl_renderer() : "");
        return d;
    }

private:
    uint64_t limit_ = 0;
    std::shared_ptr<const StageStore> store_;
    FrontierTruths truths_;   // frontier_point's truths (on worker_'s thread), for the truth settings truths_for_
    std::string truths_for_;
    Worker worker_;
    std::unique_ptr<Workbench> wb_;  // made and destroyed on worker_'s thread
};

// [SECTION] Module
py::dict schema_dict(const std::string& technique) {
    const std::vector<const ParamGroup*> groups = schema_groups(technique, "schema");
    json all = json::object();
    for (const ParamGroup* g : groups) {
        const json group = group_schema(*g);
        for (json p : group["params"]) {
            const std::string key = p["key"];
            p.erase("key");
            json range = nullptr;
            if (p.contains("choices")) range = p["choices"];
            else if (p.contains("min") || p.contains("max")) range = json::array({p.value("min", json(nullptr)), p.value("max", json(nullptr))});
            p["range"] = range;
            if (!p.contains("unit")) p["unit"] = "";
            all[key] = p;
        }
    }
    return from_json(all);
}
}  // namespace

PYBIND11_MODULE(MESOLAB_MODULE_NAME, m) {
    m.doc() = "mesolab: meso-scale appearance (micro-geometry, bump synthesis, translucency, cloth) from Python. See python/README.md.";
    m.attr("__version__") = version_string();
    gpu::install_headless_renderer();  // backend="gpu" (its context is made on first use), also before any Workbench
    // MESOLAB_THREADS=N: this process uses at most N threads (a cluster's workers, one per core
    // group, each capped so that they do not oversubscribe the machine). Unset: every core.
    if (const char* t = std::getenv("MESOLAB_THREADS"); t && *t) {
        char* end = nullptr;
        const long n = std::strtol(t, &end, 10);
        if (!end || *end || n < 1 || n > 4096) throw InputError(std::string("MESOLAB_THREADS: expected a thread count 1..4096, got '") + t + "'");
        static tbb::global_control cap(tbb::global_control::max_allowed_parallelism, size_t(n));
    }

    // [SECTION] Errors (the translators run newest first: the subclass before its base)
    static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
    static py::exception<MemoryBudgetError> memory_error(m, "MemoryBudgetError", input_error.ptr());
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const MemoryBudgetError& e) {
            memory_error(e.what());
        } catch (const InputError& e) {
            input_error(e.what());
        } catch (const Cancelled&) {
            PyErr_SetString(PyExc_KeyboardInterrupt, "cancelled");
        } catch (const std::bad_alloc&) {
            memory_error("out of memory: the settings need more memory than this machine has; lower the resolutions, direction counts or frame size (mesolab.schema() lists them)");
        }
    });

    // [SECTION] Scene
    py::class_<PyScene>(m, "Scene", "A scene: every parameter of a preset, checked as `--set` checks it.")
        .def(py::init([](const std::string& technique) {
                 if (!Registry::instance().technique(technique)) {
                     const std::string hint = nearest_key(technique, Registry::instance().technique_names());
                     throw InputError("Scene: unknown technique '" + technique + "'" + (hint.empty() ? "" : " (did you mean '" + hint + "'?)") +
                                      "; techniques: " + join(Registry::instance().technique_names(), ", "));
                 }
                 return PyScene{default_scene(technique), {}};
             }),
             py::arg("technique") = "basic", "One sphere with `technique`, one directional light and a grey environment.")
        .def_static(
            "from_json",
            [](const std::string& text, const std::string& base_dir) {
                json j;
                try {
                    j = json::parse(text);
                } catch (const json::parse_error& e) {
                    throw InputError(std::string("scene JSON: ") + e.what());
                }
                return PyScene{scene_from_json(j, "scene JSON", fs::absolute(base_dir).lexically_normal().string()), {}};
            },
            py::arg("text"), py::arg("base_dir") = ".", "A scene from preset JSON text; relative paths in it are relative to base_dir.")
        .def("to_json", [](const PyScene& s) { return scene_to_text(s.scene); }, "The preset JSON (every used parameter, declaration order).")
        .def(
            "save",
            [](const PyScene& s, const py::object& path, bool pack) {
                s.check_used();
                const std::string p = path_arg(path);
                if (pack || is_pack(p)) {
                    write_pack(s.scene, p);
                    return;
                }
                save_preset(s.scene, p);
            },
            py::arg("path"), py::kw_only(), py::arg("pack") = false,
            "Write the preset through a temporary file renamed over `path`: the old file survives any failure. With pack=True (or a path "
            "ending in .zip) a pack to share: the preset with every file it names, arrays given from Python included, as NAME.zip or a folder.")
        .def("set", &PyScene::set, py::arg("key"), py::arg("value"), py::arg("object") = py::none(),
             "Set a public key (as --set KEY=VALUE): type and range are checked at once. TECHNIQUE.* and geometry.* keys "
             "address every object of that technique (the first object) unless object= names an index or a name.")
        .def(
            "update",
            [](PyScene& s, const py::dict& values, const py::object& object) {
                for (const auto& [k, v] : values) s.set(k.cast<std::string>(), py::reinterpret_borrow<py::object>(v), object);
            },
            py::arg("values"), py::arg("object") = py::none(), "set() for each key of a dict, in its order.")
        .def("get", &PyScene::get, py::arg("key"), py::arg("object") = py::none(),
             "A key's value as a plain Python value (bool, int, float, str, tuple).")
        .def("__setitem__", [](PyScene& s, const std::string& key, const py::object& value) { s.set(key, value, py::none()); })
        .def("__getitem__", [](const PyScene& s, const std::string& key) { return s.get(key, py::none()); })
        .def("__contains__", [](const PyScene& s, const std::string& key) {
            try {
                decl_of(s.scene, key);
                return true;
            } catch (const InputError&) {
                return false;
            }
        })
        .def("keys", [](const PyScene& s) { return public_keys(s.scene); }, "Every public key of this scene.")
        .def("copy", [](const PyScene& s) { return s; })
        .def("__copy__", [](const PyScene& s) { return s; })
        .def("__deepcopy__", [](const PyScene& s, const py::dict&) { return s; }, py::arg("memo"))
        .def("__eq__", [](const PyScene& a, const PyScene& b) { return a.scene == b.scene; })
        .def_property(
            "name", [](const PyScene& s) { return s.scene.name; }, [](PyScene& s, const std::string& n) { s.scene.name = n; },
            "The preset's name (capture file names).")
        .def_property(
            "description", [](const PyScene& s) { return s.scene.description; }, [](PyScene& s, const std::string& d) { s.scene.description = d; })
        .def_property_readonly("base_dir", [](const PyScene& s) { return s.scene.base_dir; })
        .def_property_readonly(
            "objects",
            [](const PyScene& s) {
                py::list l;
                for (const auto& o : s.scene.objects) l.append(py::dict(py::arg("name") = o.name, py::arg("technique") = o.technique));
                return l;
            },
            "The scene's objects: [{name, technique}], in index order.")
        .def("__repr__", [](const PyScene& s) {
            std::vector<std::string> objects;
            for (const auto& o : s.scene.objects) objects.push_back(o.name + " (" + o.technique + ")");
            return "<mesolab.Scene '" + s.scene.name + "': " + join(objects, ", ") + ">";
        });

    // [SECTION] For the cluster layer (mesolab/cluster.py): packs and partial truths as bytes
    m.def(
        "_pack_bytes", [](const PyScene& s) {
            s.check_used();
            return py::bytes(pack_bytes(s.scene));
        },
        py::arg("scene"), "The scene as a zip pack's bytes (core/pack.h), the same bytes for the same scene and files.");
    m.def(
        "_load_pack_bytes", [](const py::bytes& b, const std::string& name) { return PyScene{load_pack_bytes(std::string(b), name), {}}; },
        py::arg("data"), py::arg("name") = "pack", "The scene of a zip pack's bytes (unpacked once into the cache's packs/ folder).");
    m.def(
        "_content_hash", [](const py::bytes& b) { return content_hash(std::string(b)); }, py::arg("data"), "FNV-1a 64 of the bytes, 16 hex digits.");
    m.def("_truth_build", [] { return truth_build(version_string()); }, "The build a truth's samples come from (version, compiler, instruction set).");
    m.def(
        "_merge_truth_parts",
        [](const std::vector<std::pair<std::string, py::bytes>>& parts) {
            std::vector<std::pair<std::string, TruthPart>> named;
            for (const auto& [name, b] : parts) named.emplace_back(name, truth_part_from_bytes(std::string(b), name));
            return py::bytes(truth_part_bytes(merge_truth_parts(named)));
        },
        py::arg("parts"), "Joins partial truths' bytes [(name, bytes)] into one (exact sums: the same bytes in any order); InputError as `truth merge`.");
    m.def(
        "_truth_part_info",
        [](const py::bytes& b) {
            const TruthPart p = truth_part_from_bytes(std::string(b), "a partial truth");
            py::dict d;
            d["scene"] = p.scene, d["key"] = p.key, d["build"] = p.build;
            d["first"] = p.sums.first, d["end"] = p.sums.spp, d["seed"] = p.sums.seed;
            d["size"] = py::make_tuple(p.sums.width, p.sums.height);
            return d;
        },
        py::arg("part"), "What a partial truth's bytes hold: {scene, key, build, first, end, seed, size}.");

    m.attr("_truth_block") = kTruthBlock;
    m.attr("_noise_min_spp") = kNoiseMinSpp;
    m.def(
        "_truth_cached",
        [](const PyScene& s, const py::object& size, uint64_t seed) -> py::object {
            const auto [w, h] = frame_size_arg(size);
            const std::string key = truth_cache_key(version_string(), s.scene, w, h, seed);
            std::optional<TruthAccumulator> a;
            {
                py::gil_scoped_release nogil;
                a = TruthCache(cache_folder("truth"), version_string()).load(key);  // this build's entries only
            }
            if (!a || a->first != 0 || a->spp < 1 || a->width != w || a->height != h || a->seed != seed) return py::none();
            return py::bytes(truth_part_bytes(TruthPart{s.scene.name, key, truth_build(version_string()), *a}));
        },
        py::arg("scene"), py::arg("size"), py::arg("seed"),
        "This machine's cached truth of the scene at this size and seed (samples from 0) as a partial truth's bytes, or None.");
    m.def(
        "_truth_sampling",
        [](const py::object& spp, const py::object& noise, const py::object& time_limit, uint64_t seed) {
            const TruthSettings st = truth_sampling_arg(spp, noise, time_limit, seed);
            py::dict d;
            d["spp"] = st.spp, d["noise"] = st.noise, d["time_limit"] = st.time_limit_s, d["seed"] = st.seed;
            return d;
        },
        py::arg("spp"), py::arg("noise"), py::arg("time_limit"), py::arg("seed"),
        "A truth's sampling as render() checks it: {spp (the most samples with a target), noise, time_limit (0: none), seed}.");
    m.def(
        "_truth_part_noise",
        [](const py::bytes& b) {
            const TruthPart p = truth_part_from_bytes(std::string(b), "a partial truth");
            py::gil_scoped_release nogil;
            return truth_noise_rel(p.sums);
        },
        py::arg("part"), "The noise_rel of a partial truth's samples (what a noise target is judged on).");
    m.def(
        "_truth_key",
        [](const PyScene& s, const py::object& size, uint64_t seed) {
            const auto [w, h] = frame_size_arg(size);
            return truth_cache_key(version_string(), s.scene, w, h, seed);
        },
        py::arg("scene"), py::arg("size"), py::arg("seed"), "The truth cache's key of the scene's truth at this size and seed (what the truth reads).");
    m.def(
        "_sweep_reference",
        [](const PyScene& s, const std::string& knob, const py::sequence& values, const py::object& reference) {
            SweepKnob k;
            k.key = knob;
            for (const py::handle& v : values) k.values.push_back(to_set_text(knob, v));
            if (k.values.empty()) throw InputError("sweep: values is empty; give the knob's settings, e.g. values=[8, 16, 32]");
            std::vector<std::pair<std::string, std::string>> given;
            if (!reference.is_none())
                for (const auto& [key, v] : reference.cast<py::dict>()) given.emplace_back(key.cast<std::string>(), to_set_text(key.cast<std::string>(), v));
            py::dict out;
            for (const auto& [key, v] : sweep_reference(s.scene, k, given)) out[py::str(key)] = v;
            return out;
        },
        py::arg("scene"), py::arg("knob"), py::arg("values"), py::arg("reference") = py::none(),
        "What a sweep measures against: {KEY: VALUE text}, as the one-process sweep chooses it.");
    m.def(
        "_frontier_settings",
        [](const PyScene& s, const py::dict& options) {
            s.check_used();
            py::list out;
            for (const FrontierSetting& st : frontier_settings(s.scene, frontier_options(options))) out.append(frontier_setting_dict(st));
            return out;
        },
        py::arg("scene"), py::arg("options"), "A frontier's first round: [{method, setting, knobs}] in the order the one-process frontier measures them.");
    m.def(
        "_frontier_between",
        [](const PyScene& s, const py::list& points) {
            std::vector<FrontierPoint> measured;
            for (const py::handle& p : points) measured.push_back(frontier_point_of(p.cast<py::dict>()));
            py::list out;
            for (const FrontierSetting& st : frontier_between(s.scene, measured)) out.append(frontier_setting_dict(st));
            return out;
        },
        py::arg("scene"), py::arg("points"), "A frontier's second round at one distance, between the first round's frontier `points`: [{method, setting, knobs}].");
    m.def(
        "_frontier_report",
        [](const PyScene& s, const py::dict& options, const py::list& points, const std::vector<double>& truth_noise, bool budget_reached,
           const std::vector<std::string>& skipped, const std::string& machine, const py::object& out_dir) {
            FrontierOptions o = frontier_options(options);
            FrontierResult partial;
            for (const py::handle& p : points) partial.points.push_back(frontier_point_of(p.cast<py::dict>()));
            partial.truth_noise = truth_noise, partial.budget_reached = budget_reached, partial.skipped = skipped, partial.machine = machine;
            if (!out_dir.is_none()) o.out_dir = path_arg(out_dir);
            const FrontierResult r = frontier_report(s.scene, o, std::move(partial), !out_dir.is_none());
            py::list out;
            for (const FrontierPoint& p : r.points) out.append(frontier_point_dict(p));
            py::dict d;
            d["points"] = out, d["markdown"] = r.markdown, d["written"] = r.written;
            return d;
        },
        py::arg("scene"), py::arg("options"), py::arg("points"), py::arg("truth_noise"), py::arg("budget_reached"), py::arg("skipped"),
        py::arg("machine"), py::arg("out_dir") = py::none(),
        "A frontier's result from its points: {points (on_frontier marked), markdown, written}; the files with out_dir=.");
    m.def(
        "_bench_rows",
        [](const py::object& tables) {
            std::vector<std::string> names;
            if (py::isinstance<py::str>(tables)) names = {tables.cast<std::string>()};
            else if (!tables.is_none()) names = tables.cast<std::vector<std::string>>();
            std::vector<std::string> known;
            py::list out;
            for (const BenchTable& t : bench_tables()) {
                known.push_back(t.name);
                if (!names.empty() && std::find(names.begin(), names.end(), t.name) == names.end()) continue;
                for (const BenchRow& r : t.rows) out.append(py::make_tuple(t.name, r.name));
            }
            for (const auto& n : names)
                if (std::find(known.begin(), known.end(), n) == known.end())
                    throw InputError("bench: unknown table '" + n + "'" + (nearest_key(n, known).empty() ? "" : " (did you mean '" + nearest_key(n, known) + "'?)") +
                                     "; tables: " + join(known, ", "));
            return out;
        },
        py::arg("tables") = py::none(), "[(table, row)] of the timing tables (all when none named), in their order.");

    m.def(
        "load_preset",
        [](const py::object& path) { return PyScene{load_preset(path_arg(path)), {}}; },
        py::arg("path"), "Load a preset file: every key is checked, errors name the file and the key.");

    // [SECTION] Frame
    py::class_<PyFrame>(m, "Frame", "A rendered frame. Arrays are read-only float32 views (H, W, C) of the frame's linear values.")
        .def("__getitem__", &PyFrame::array, py::arg("aov"))
        .def("__contains__", [](const PyFrame& f, const std::string& a) { return f.r->frame.has(a); })
        .def_property_readonly("aovs", &PyFrame::aov_names, "The AOVs the frame holds (radiance first).")
        .def_property_readonly("width", [](const PyFrame& f) { return f.r->frame.width; })
        .def_property_readonly("height", [](const PyFrame& f) { return f.r->frame.height; })
        .def_property_readonly("size", [](const PyFrame& f) { return py::make_tuple(f.r->frame.width, f.r->frame.height); })
        .def_property_readonly("renderer", [](const PyFrame& f) { return f.r->renderer; }, "'cpu', 'truth' or the GL renderer.")
        .def_property_readonly("stages", [](const PyFrame& f) { return from_json(f.sidecar()["stages"]); },
                               "The stages of the evaluation, as the capture's sidecar: [{name, status, ms, ...}].")
        .def_property_readonly("frame_steps", [](const PyFrame& f) { return from_json(f.sidecar()["frame_steps"]); })
        .def_property_readonly("timings", [](const PyFrame& f) { return from_json(f.sidecar()["timings"]); },
                               "{stages_ms, render_ms[, gpu_ms]} as the capture's sidecar.")
        .def_property_readonly(
            "truth",
            [](const PyFrame& f) -> py::object {
                json j = f.sidecar();
                return j.contains("truth") ? from_json(j["truth"]) : py::none();
            },
            "With aovs=['truth_error'] or backend='truth': the truth's settings and the comparison, else None.")
        .def("sidecar", [](const PyFrame& f) { return from_json(f.sidecar()); }, "What the capture's JSON sidecar holds.")
        .def("save", &PyFrame::save, py::arg("dir"),
             "Write the capture's files into dir: NAME.png, NAME.<aov>.exr for every AOV, NAME.json. Returns the paths.")
        .def("_repr_png_", &PyFrame::png)
        .def("__repr__", &PyFrame::repr);

    // [SECTION] Workbench
    py::class_<PyWorkbench>(m, "Workbench",
                            "One session: the stage cache, the memory budget and a headless GL context, on a thread of its own. "
                            "Two workbenches share nothing and may render from two Python threads at once.")
        .def(py::init<const py::object&>(), py::arg("memory_limit") = py::none(),
             "memory_limit: '2G', '512M' or bytes (default: the machine's available memory).")
        .def("render", &PyWorkbench::render, py::arg("scene"), py::kw_only(), py::arg("size") = py::make_tuple(512, 512), py::arg("backend") = "gpu",
             py::arg("aovs") = std::vector<std::string>{}, py::arg("spp") = py::none(), py::arg("seed") = 1, py::arg("noise") = py::none(),
             py::arg("time_limit") = py::none(), py::arg("progress") = py::none(),
             "Render a frame: backend 'gpu' (the CLI's default), 'cpu' or 'truth' (spp: 64 by default; seed). The truth samples until its "
             "noise_rel reaches noise= (e.g. 0.01) or time_limit= seconds pass, continuing the cached truth (spp is then the most samples, "
             "unlimited when not given); frame.truth['ended'] says which. aovs beside radiance; 'truth_error' also renders the truth. "
             "progress(stage, fraction) is called from this thread; Ctrl-C stops the work.")
        .def("_truth_part", &PyWorkbench::truth_part, py::arg("scene"), py::arg("size"), py::arg("seed"), py::arg("first"), py::arg("end"),
             py::arg("progress") = py::none(), "Samples [first, end) of the scene's truth as a partial truth's bytes (the cluster layer's task).")
        .def(
            "_frontier_point",
            [](PyWorkbench& w, const PyScene& ps, const py::dict& options, double distance, const py::dict& setting, const py::object& poll) {
                return w.frontier_point(ps, frontier_options(options), distance, frontier_setting_of(setting), poll);
            },
            py::arg("scene"), py::arg("options"), py::arg("distance"), py::arg("setting"), py::arg("poll") = py::none(),
            "One frontier setting ({method, setting, knobs}) at one distance, timed and measured on this workbench (its truth from the truth "
            "cache): {point (or None), skipped, stopped, truth_noise, machine}. poll() is called every 50 ms: raising stops the work (cancelled), "
            "returning True ends the budget (a setting not a preset stops unless its frame is already rendered: stopped).")
        .def("_truth_from_part", &PyWorkbench::truth_from_part, py::arg("scene"), py::arg("part"), py::arg("progress") = py::none(),
             py::arg("noise") = 0.0, py::arg("time_limit") = 0.0, py::arg("ended") = "samples",
             "The frame of a merged truth's bytes (samples from 0), as render(backend='truth') gives it; kept in the truth cache.")
        .def_property_readonly("gl_renderer", &PyWorkbench::gl_renderer)
        .def_property_readonly("memory_limit", &PyWorkbench::memory_limit, "In bytes; 0: the machine's available memory.")
        .def("clear_cache", &PyWorkbench::clear_cache, "Forget every cached stage result and frame step.")
        .def("close", &PyWorkbench::close, "Free the caches and the GL context now; the workbench cannot render afterwards.")
        .def("__enter__", [](py::object self) { return self; })
        .def("__exit__", [](PyWorkbench& w, const py::args&) { w.close(); })
        .def_property_readonly("cache_entries", &PyWorkbench::cache_entries);

    // [SECTION] Module functions
    m.def(
        "info",
        [] {
            std::vector<std::pair<std::string, std::string>> fields;
            {
                py::gil_scoped_release nogil;
                fields = info_fields();
            }
            py::dict d;
            for (auto [k, v] : fields) {
                std::replace(k.begin(), k.end(), ' ', '_');  // "gl renderer" -> gl_renderer
                d[py::str(k)] = v;
            }
            return d;
        },
        "What `mesolab info` prints, as a dict.");
    m.def("schema", &schema_dict, py::arg("technique") = "",
          "Every parameter: {key: {type, default, range, unit, help, cost, ...}}; technique= (or a group: camera, light, env, geometry, effects) narrows it.");
    m.def(
        "bench",
        [](const py::object& tables, int repeat, const std::string& backend, const std::vector<std::string>& rows, const std::vector<std::string>& columns,
           const py::object& noise, const py::object& time_limit, const py::object& memory_limit, const py::object& presets, const py::object& progress,
           const py::object& on) {
            BenchOptions o;
            if (!presets.is_none())
                for (const py::handle& p : presets.cast<py::sequence>()) o.presets.push_back(path_arg(py::reinterpret_borrow<py::object>(p)));
            if (!noise.is_none()) {
                const TruthSettings st = truth_sampling_arg(py::none(), noise, time_limit.is_none() ? py::float_(600.0) : time_limit, 1);
                o.noise = st.noise;
                o.time_limit_s = st.time_limit_s;
            } else if (!time_limit.is_none()) {
                throw InputError("bench: time_limit= bounds the truth table's noise= runs; add noise=");
            }
            if (py::isinstance<py::str>(tables)) o.tables = {tables.cast<std::string>()};
            else if (!tables.is_none()) o.tables = tables.cast<std::vector<std::string>>();
            o.repeat = repeat, o.backend = backend, o.rows = rows, o.columns = columns, o.quiet = true;
            o.memory_limit = memory_limit_arg(memory_limit);
            const auto work = [&](Workbench* wb, const ProgressFn& p, const std::atomic<bool>* cancel) {
                BenchOptions run = o;
                run.progress = p, run.cancel = cancel, run.workbench = wb;
                return measure_bench(run);
            };
            const BenchResult r =
                on.is_none() ? run_alone<BenchResult>(progress, [&](const ProgressFn& p, const std::atomic<bool>* c) { return work(nullptr, p, c); })
                             : on.cast<PyWorkbench&>().borrow<BenchResult>(progress, o.memory_limit, [&](Workbench& wb, const ProgressFn& p, const std::atomic<bool>* c) {
                                   return work(&wb, p, c);
                               });
            py::list cells;
            for (const BenchCell& c : r.cells) {
                py::dict d;
                d["table"] = c.table, d["row"] = c.row, d["column"] = c.column;
                if (!c.step.empty()) d["step"] = c.step;
                if (!c.info.empty()) {
                    d["info"] = c.info;
                } else {
                    d["device"] = c.device, d["median_ms"] = c.median, d["min_ms"] = c.min, d["max_ms"] = c.max;
                    if (c.gpu_time) d["gpu_time_ms"] = *c.gpu_time;
                    if (c.paper) d["paper_ms"] = *c.paper, d["paper_over_ours"] = *c.paper / c.median;
                }
                cells.append(d);
            }
            return cells;
        },
        py::arg("tables") = py::none(), py::kw_only(), py::arg("repeat") = 5, py::arg("backend") = "both", py::arg("rows") = std::vector<std::string>{},
        py::arg("columns") = std::vector<std::string>{}, py::arg("noise") = py::none(), py::arg("time_limit") = py::none(), py::arg("memory_limit") = py::none(),
        py::arg("presets") = py::none(), py::arg("progress") = py::none(), py::arg("_on") = py::none(),
        "Measure timing tables (all when none named) as `mesolab bench --format json`: a list of its cells "
        "({table, row, column, device, median_ms, min_ms, max_ms, ...}). noise= (table 'truth'): each preset's time to that noise_rel, "
        "measured, giving up after time_limit= seconds (600 by default). presets= (table 'truth'): a row for each of these presets or packs instead of the shipped ones.");
    m.def(
        "frontier",
        [](const PyScene& scene, const py::object& size, const std::string& backend, const std::vector<double>& distances, const py::object& spp,
           uint64_t seed, const py::object& noise, const py::object& time_limit, double budget, int repeat, const py::object& out_dir,
           const py::object& memory_limit, const py::object& progress) {
            scene.check_used();
            FrontierOptions o = frontier_options(size, backend, distances, spp, seed, noise, time_limit, budget, repeat, memory_limit);
            if (!out_dir.is_none()) o.out_dir = path_arg(out_dir);
            const FrontierResult r = run_alone<FrontierResult>(progress, [&](const ProgressFn& p, const std::atomic<bool>* cancel) {
                FrontierOptions run = o;
                run.progress = p, run.cancel = cancel;
                return frontier_scene(scene.scene, run, !out_dir.is_none());
            });
            py::list out;
            for (const FrontierPoint& p : r.points) out.append(frontier_point_dict(p));
            return out;
        },
        py::arg("scene"), py::kw_only(), py::arg("size") = py::make_tuple(128, 128), py::arg("backend") = "cpu", py::arg("distances") = std::vector<double>{},
        py::arg("spp") = py::none(), py::arg("seed") = 1, py::arg("noise") = py::none(), py::arg("time_limit") = py::none(), py::arg("budget") = 600.0,
        py::arg("repeat") = 3, py::arg("out_dir") = py::none(), py::arg("memory_limit") = py::none(), py::arg("progress") = py::none(),
        "The accuracy-time frontier, as `mesolab frontier`: every accuracy knob of the scene's methods on a coarse grid and all together, each setting "
        "timed (frame_ms with its stages cached, precompute_ms from a cold cache) and measured against one truth per distance (rmse_rel); "
        "[{distance, method, setting, knobs, frame_ms, precompute_ms, rmse_rel, below_noise, on_frontier}]. budget= seconds; files only with out_dir=.");
    m.def(
        "sweep",
        [](const PyScene& scene, const std::string& knob, const py::sequence& values, const py::object& size, const std::string& metric,
           const std::string& backend, int repeat, const py::object& reference, const py::object& by, const py::object& by_values, const py::object& spp,
           uint64_t seed, const py::object& noise, const py::object& time_limit, const py::object& out_dir, const py::object& memory_limit,
           const py::object& progress, const py::object& on) {
            scene.check_used();
            const auto [w, h] = frame_size_arg(size);
            SweepOptions o;
            o.knob.key = knob;
            for (const py::handle& v : values) o.knob.values.push_back(to_set_text(knob, v));
            if (o.knob.values.empty()) throw InputError("sweep: values is empty; give the knob's settings, e.g. values=[8, 16, 32]");
            const std::vector<std::string>& texts = o.knob.values;
            o.width = w, o.height = h;
            o.metric = metric, o.backend = RendererRegistry::instance().find(backend, "backend=").name, o.repeat = repeat, o.quiet = true;
            o.truth = truth_sampling_arg(spp, noise, time_limit, seed);  // checked here, with the Python names
            if (!reference.is_none())
                for (const auto& [k, v] : reference.cast<py::dict>()) o.reference.emplace_back(k.cast<std::string>(), to_set_text(k.cast<std::string>(), v));
            std::vector<py::object> by_list;
            if (!by.is_none()) {
                if (by_values.is_none()) throw InputError("sweep: by= needs by_values=[...]");
                o.by.key = by.cast<std::string>();
                for (const py::handle& v : by_values.cast<py::sequence>())
                    o.by.values.push_back(to_set_text(o.by.key, v)), by_list.push_back(py::reinterpret_borrow<py::object>(v));
            }
            o.memory_limit = memory_limit_arg(memory_limit);
            if (!out_dir.is_none()) o.out_dir = path_arg(out_dir);
            const auto work = [&](Workbench* wb, const ProgressFn& p, const std::atomic<bool>* cancel) {
                SweepOptions run = o;
                run.progress = p, run.cancel = cancel, run.workbench = wb;
                return sweep_scene(scene.scene, run, !out_dir.is_none());
            };
            const SweepResult r =
                on.is_none() ? run_alone<SweepResult>(progress, [&](const ProgressFn& p, const std::atomic<bool>* c) { return work(nullptr, p, c); })
                             : on.cast<PyWorkbench&>().borrow<SweepResult>(progress, o.memory_limit, [&](Workbench& wb, const ProgressFn& p, const std::atomic<bool>* c) {
                                   return work(&wb, p, c);
                               });
            py::list out;
            for (size_t i = 0; i < r.points.size(); ++i) {
                const SweepPoint& p = r.points[i];
                const size_t n = texts.size();
                py::dict d;
                d["value"] = values[i % n];
                if (!by_list.empty()) d["by"] = by_list[i / n];
                d["ms"] = p.ms;
                d["error"] = p.err;
                if (metric == "rmse" || metric == "truth") d["relative_error"] = p.rel;
                d["knob_ms"] = p.knob_ms;
                if (metric == "truth") d["below_noise"] = p.below_noise;
                out.append(d);
            }
            return out;
        },
        py::arg("scene"), py::kw_only(), py::arg("knob"), py::arg("values"), py::arg("size") = py::make_tuple(256, 256), py::arg("metric") = "rmse",
        py::arg("backend") = "cpu", py::arg("repeat") = 3, py::arg("reference") = py::none(), py::arg("by") = py::none(), py::arg("by_values") = py::none(),
        py::arg("spp") = py::none(), py::arg("seed") = 1, py::arg("noise") = py::none(), py::arg("time_limit") = py::none(), py::arg("out_dir") = py::none(),
        py::arg("memory_limit") = py::none(), py::arg("progress") = py::none(), py::arg("_on") = py::none(),
        "Accuracy vs time, as `mesolab sweep`: each value of the knob rendered from a cold cache, timed (median of repeat) and "
        "measured against the reference (metric 'rmse'), the truth ('truth': spp, seed, noise, time_limit as for render) or a technique's metric. Returns "
        "[{value, ms, error, ...}]; writes the CSV, Markdown and plot only with out_dir=.");
}
