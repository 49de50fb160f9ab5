// hashfusion.open_dataset, hashfusion.Pipeline (and its results), hashfusion.make_registration and the
// evaluation (hashfusion.evaluate / ate / rpe) over the C++ library.
//
// Long calls (reading a frame, process, run, extract_mesh, render, align) release the GIL. Each wrapped C++ object
// that allows one caller at a time (FrameSource::next, Pipeline, Registration) is guarded by a mutex taken after
// the GIL is released, so Python threads sharing one object queue instead of racing. Pipeline.run checks for
// signals (PyErr_CheckSignals) after every frame: Ctrl-C ends the run after the current frame and raises
// KeyboardInterrupt, the map and the pipeline keeping every frame processed (an exception from its callback
// does the same).
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <atomic>
#include <cmath>
#include <mutex>
#include <optional>
#include <sstream>

#include "core/error.h"
#include "datasets/synthetic_source.h"
#include "fusion/volume_io.h"
#include "io/dataset.h"
#include "python/src/bindings.h"
#include "python/src/convert.h"
#include "registration/frame_pyramid.h"
#include "registration/reduction.h"
#include "registration/registration.h"
#include "slam/eval.h"
#include "slam/pipeline.h"
#include "slam/pipeline_config.h"
#include "slam/sequence_run.h"

namespace hf::python {
namespace {

// Runs f() without the GIL, holding `m` (taken after the release: a thread waiting for `m` never holds the GIL).
template <class F>
auto unlocked(std::mutex& m, F&& f) {
  py::gil_scoped_release nogil;
  std::lock_guard<std::mutex> lock(m);
  return f();
}

struct Dataset {
  std::unique_ptr<FrameSource> source;
  std::string input;
  std::vector<std::string> bad_frames;
  std::mutex mutex;
};

struct Pipeline {
  std::unique_ptr<slam::Pipeline> pipeline;
  std::optional<double> last_timestamp_s;  // of the last frame processed, for the check the CLI's readers make
  std::mutex mutex;
};

// Time stamps as a TUM list file must have them (io/tum_dataset.h): finite; and not before the previous frame's,
// since the motion-plausibility check divides by the time between frames.
void check_timestamp(const Pipeline& p, double timestamp_s) {
  if (!std::isfinite(timestamp_s))
    throw ValueError("timestamp: expected a finite time in seconds, got " + std::to_string(timestamp_s));
  if (p.last_timestamp_s && timestamp_s < *p.last_timestamp_s) {
    std::ostringstream s;
    s.precision(17);
    s << "timestamp " << timestamp_s << " s is before the previous frame's " << *p.last_timestamp_s
      << " s: time stamps may not decrease";
    throw ValueError(s.str());
  }
}

slam::FrameResult process_checked(Pipeline& p, const RgbdFrame& frame) {
  check_timestamp(p, frame.timestamp_s);
  slam::FrameResult r = unlocked(p.mutex, [&] { return p.pipeline->process(frame); });
  p.last_timestamp_s = frame.timestamp_s;
  return r;
}

struct Registration {
  std::unique_ptr<hf::Registration> registration;
  std::mutex mutex;
};

struct RunResult {
  slam::SequenceRun run;
  nlohmann::json report;
};

PinholeCamera camera_argument(const py::object& camera) {
  if (py::isinstance<PinholeCamera>(camera)) return camera.cast<PinholeCamera>();
  return camera_from_option(camera.cast<std::string>()).camera;
}

std::unique_ptr<Dataset> open(const std::string& path, const py::object& camera, int frames, std::uint64_t seed,
                              size_t prefetch_frames) {
  if (!datasets::is_synthetic_input(path)) require_existing_path(path, "open_dataset");
  auto d = std::make_unique<Dataset>();
  d->input = path;
  py::gil_scoped_release nogil;
  if (datasets::is_synthetic_input(path)) {
    datasets::SyntheticOptions s;
    s.frames = frames;
    s.seed = seed;
    if (!camera.is_none()) {
      py::gil_scoped_acquire gil;
      s.camera = camera_argument(camera);
    }
    d->source = datasets::open_synthetic_input(path, s);
  } else {
    DatasetOptions o;
    o.prefetch_frames = prefetch_frames;
    if (!camera.is_none()) {
      py::gil_scoped_acquire gil;
      if (py::isinstance<PinholeCamera>(camera))
        throw ValueError("open_dataset: a dataset folder takes camera as a preset name or a camera file");
      o.camera = camera.cast<std::string>();
    }
    d->source = open_dataset(path, o);
  }
  return d;
}

// The next decoded frame; unreadable frames are skipped, recorded in bad_frames and warned about.
RgbdFrame next_frame(Dataset& d) {
  for (;;) {
    FrameRead r = unlocked(d.mutex, [&] { return d.source->next(); });
    if (r.status == FrameStatus::end) throw py::stop_iteration();
    if (r.status == FrameStatus::ok) return std::move(r.frame);
    d.bad_frames.push_back(r.message);
    PyErr_WarnEx(PyExc_RuntimeWarning, ("skipping frame: " + r.message).c_str(), 1);
  }
}

slam::PipelineConfig config_argument(const py::object& config) {
  if (config.is_none()) return {};
  slam::PipelineConfig c = slam::config_from_json(json_from_python(config, "config"), "config");
  c.validate();
  return c;
}

py::dict stage_ms(const slam::StageMs& s) {
  py::dict d;
  d["read"] = s.read, d["preprocess"] = s.preprocess, d["track"] = s.track, d["relocalise"] = s.relocalise;
  d["integrate"] = s.integrate, d["raycast"] = s.raycast, d["keyframe"] = s.keyframe, d["loop"] = s.loop;
  d["reintegrate"] = s.reintegrate, d["total"] = s.total();
  return d;
}

RunResult run(Pipeline& p, Dataset& d, long max_frames, bool global, const py::object& callback) {
  std::atomic<bool> stop{false};
  std::optional<py::error_already_set> error;  // from the callback or a signal handler
  slam::RunControl control;
  control.max_frames = max_frames;
  control.stop = &stop;
  control.warn_bad_frames = false;
  control.global = global;
  control.on_frame = [&](const slam::FrameResult& r) {
    py::gil_scoped_acquire gil;
    if (error) return;
    try {
      if (!callback.is_none()) callback(r);
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();  // e.g. KeyboardInterrupt from Ctrl-C
    } catch (py::error_already_set& e) {  // stop after this frame, raise once the run has ended
      error.emplace(std::move(e));
      stop = true;
    }
  };
  RunResult result;
  {
    py::gil_scoped_release nogil;
    std::scoped_lock lock(p.mutex, d.mutex);
    result.run = slam::run_sequence(*d.source, *p.pipeline, control);
    const slam::RunSummary summary = slam::summarize(result.run, *p.pipeline, *d.source, d.input);
    result.report = slam::summary_to_json(summary, result.run, *p.pipeline, *d.source);
  }
  for (const auto& b : result.run.bad_frames) d.bad_frames.push_back(b);
  const Trajectory online = result.run.online_estimate();
  if (!online.empty()) p.last_timestamp_s = online.back().timestamp_s;
  if (error) throw *error;
  return result;
}

py::dict ate_dict(const AteResult& ate, const nlohmann::json& metrics) {
  py::dict d;
  for (auto it = metrics.begin(); it != metrics.end(); ++it)
    if (it.key() == "pairs" || it.key().rfind("ate_", 0) == 0) d[py::str(it.key())] = json_to_python(it.value());
  d["T_gt_est"] = se3_to_array(ate.T_gt_est);
  py::array_t<double> errors(py::ssize_t(ate.pairs.size()));
  for (size_t i = 0; i < ate.pairs.size(); ++i) errors.mutable_at(py::ssize_t(i)) = ate.pairs[i].error_m;
  d["errors_m"] = errors;
  return d;
}

py::dict rpe_dict(const RpeResult& rpe, const nlohmann::json& metrics) {
  py::dict d;
  for (auto it = metrics.begin(); it != metrics.end(); ++it)
    if (it.key().rfind("rpe_", 0) == 0) d[py::str(it.key())] = json_to_python(it.value());
  py::array_t<double> trans(py::ssize_t(rpe.pairs.size())), rot(py::ssize_t(rpe.pairs.size()));
  for (size_t i = 0; i < rpe.pairs.size(); ++i) {
    trans.mutable_at(py::ssize_t(i)) = rpe.pairs[i].trans_m_per_s;
    rot.mutable_at(py::ssize_t(i)) = rpe.pairs[i].rot_deg_per_s;
  }
  d["trans_m_per_s"] = trans;
  d["rot_deg_per_s"] = rot;
  return d;
}

// Frame `index` out of order (negative counts from the end, as Python's); IndexError outside, hf.Error for an
// unreadable frame. Does not move the iteration.
RgbdFrame frame_at(const Dataset& d, long index) {
  const size_t n = d.source->size();
  if (n == kUnknownFrameCount) throw py::type_error("a live source cannot be indexed");
  const long i = index < 0 ? index + long(n) : index;
  if (i < 0 || size_t(i) >= n)
    throw py::index_error("frame " + std::to_string(index) + " out of range (" + std::to_string(n) + " frames)");
  std::optional<FrameRead> r;
  {
    py::gil_scoped_release nogil;
    r = d.source->read_at(size_t(i));
  }
  if (!r) throw py::type_error("this source cannot be indexed");
  if (r->status != FrameStatus::ok) throw Error(r->message);
  return std::move(r->frame);
}

void bind_dataset(py::module_& m) {
  py::class_<Dataset>(m, "Dataset",
                      "Frames of a dataset folder (TUM RGB-D, 7-Scenes) or synthetic:PRESET: iterate it, or index "
                      "it (data[i], data[a:b:s] a lazy view, len(data)); indexing does not move the iteration")
      .def("__iter__", [](py::object self) { return self; })
      .def("__next__", &next_frame)
      .def("__len__",
           [](const Dataset& d) {
             if (d.source->size() == kUnknownFrameCount) throw py::type_error("a live source has no length");
             return d.source->size();
           })
      .def("_frame_at", &frame_at, py::arg("index"), "frame `index` (the Python side implements data[i])")
      .def_property_readonly("camera", [](const Dataset& d) { return d.source->camera(); })
      .def_property_readonly("camera_origin", [](const Dataset& d) { return d.source->camera_origin(); })
      .def_property_readonly("name", [](const Dataset& d) { return d.source->name(); })
      .def_property_readonly("ground_truth",
                             [](const Dataset& d) { return trajectory_to_python(d.source->ground_truth()); })
      .def_readonly("bad_frames", &Dataset::bad_frames, "one line per skipped (unreadable) frame");
  m.def("open_dataset", &open, py::arg("path"), py::arg("camera") = py::none(), py::arg("frames") = 90,
        py::arg("seed") = 0, py::arg("prefetch_frames") = 4,
        "Opens a TUM RGB-D or 7-Scenes folder, or 'synthetic:PRESET' (frames, seed: of a synthetic sequence; "
        "camera: a preset name or camera file, or for synthetic input a Camera).");
}

void bind_results(py::module_& m) {
  py::class_<RegistrationResult>(m, "RegistrationResult")
      .def_property_readonly("status", [](const RegistrationResult& r) { return std::string(to_string(r.status)); })
      .def_property_readonly("T_ref_cur", [](const RegistrationResult& r) { return se3_to_array(r.T_ref_cur); })
      .def_readonly("information", &RegistrationResult::information, "6x6 J^T W J, xi = (omega, v) order")
      .def_readonly("eigenvalues", &RegistrationResult::eigenvalues)
      .def_readonly("condition_number", &RegistrationResult::condition_number)
      .def_readonly("degenerate_dims", &RegistrationResult::degenerate_dims)
      .def_readonly("weakest_direction", &RegistrationResult::weakest_direction)
      .def_readonly("iterations_per_level", &RegistrationResult::iterations_per_level)
      .def_readonly("final_cost", &RegistrationResult::final_cost)
      .def_readonly("inliers", &RegistrationResult::inliers)
      .def_readonly("inlier_ratio", &RegistrationResult::inlier_ratio)
      .def_readonly("message", &RegistrationResult::message)
      .def("usable", &RegistrationResult::usable);
  py::class_<slam::FrameResult>(m, "FrameResult")
      .def_readonly("index", &slam::FrameResult::index)
      .def_readonly("timestamp", &slam::FrameResult::timestamp_s)
      .def_property_readonly("state", [](const slam::FrameResult& r) { return std::string(slam::to_string(r.state)); })
      .def_property_readonly("T_world_camera",
                             [](const slam::FrameResult& r) { return se3_to_array(r.T_world_camera); })
      .def_readonly("pose_valid", &slam::FrameResult::pose_valid)
      .def_readonly("integrated", &slam::FrameResult::integrated)
      .def_readonly("keyframe", &slam::FrameResult::keyframe)
      .def_readonly("loop_closed", &slam::FrameResult::loop_closed)
      .def_readonly("method", &slam::FrameResult::method)
      .def_readonly("registration", &slam::FrameResult::registration)
      .def_readonly("message", &slam::FrameResult::message)
      .def_readonly("seeded_on_failure", &slam::FrameResult::seeded_on_failure)
      .def_readonly("placed_by_seed", &slam::FrameResult::placed_by_seed)
      .def_readonly("wide_basin", &slam::FrameResult::wide_basin)
      .def_property_readonly("ms", [](const slam::FrameResult& r) { return stage_ms(r.ms); });
  py::class_<RunResult>(m, "RunResult")
      .def_property_readonly("frames", [](const RunResult& r) { return r.run.frames; })
      .def_property_readonly("trajectory", [](const RunResult& r) { return trajectory_to_python(r.run.estimate()); },
                             "what trajectory.txt holds: every frame, corrected poses where loop closure moved them")
      .def_property_readonly("online_trajectory",
                             [](const RunResult& r) { return trajectory_to_python(r.run.online_estimate()); })
      .def_property_readonly("interrupted", [](const RunResult& r) { return r.run.interrupted; })
      .def_property_readonly("stopped_by", [](const RunResult& r) { return r.run.stopped_by; })
      .def_property_readonly("bad_frames", [](const RunResult& r) { return r.run.bad_frames; })
      .def_property_readonly("report", [](const RunResult& r) { return json_to_python(r.report); },
                             "report.json's content (without \"outputs\")");
}

void bind_pipeline(py::module_& m) {
  py::class_<Pipeline>(m, "Pipeline", "Tracking + fusion; config: a dict with report.json's \"config\" keys")
      .def(py::init([](const py::object& config, const PinholeCamera& camera) {
             auto p = std::make_unique<Pipeline>();
             const slam::PipelineConfig c = config_argument(config);
             py::gil_scoped_release nogil;
             p->pipeline = std::make_unique<slam::Pipeline>(c, camera);
             return p;
           }),
           py::arg("config") = py::none(), py::arg("camera") = PinholeCamera{})
      .def("process", &process_checked, py::arg("frame"),
           "a Frame; its timestamp must be finite and not before the previous frame's (ValueError)")
      .def("process",
           [](Pipeline& p, const py::object& depth, const py::object& color, double timestamp,
              const py::object& T_world_camera_gt, const py::object& depth_scale) {
             const RgbdFrame f = frame_from_arrays(depth, color, timestamp, T_world_camera_gt,
                                                   p.pipeline->frames_processed(), depth_scale);
             return process_checked(p, f);
           },
           py::arg("depth"), py::arg("color"), py::arg("timestamp"), py::arg("T_world_camera_gt") = py::none(),
           py::arg("depth_scale") = py::none(),
           "depth float32 (H, W) metres or uint16 with depth_scale units per metre, color uint8 (H, W, 3), "
           "timestamp seconds (finite, not before the previous frame's)")
      .def("run", &run, py::arg("dataset"), py::arg("max_frames") = 0, py::arg("global_solve") = false,
           py::arg("callback") = py::none(),
           "the whole dataset as `hashfusion run` does it; callback(FrameResult) after each frame. Ctrl-C, or an "
           "exception from callback, stops after the current frame and is raised")
      .def("finish",
           [](Pipeline& p, bool global) { return unlocked(p.mutex, [&] { return p.pipeline->finish(global); }); },
           py::arg("global_solve") = false, "after the last frame: drain the re-fusion queue; returns ms")
      .def("save",
           [](Pipeline& p, const std::string& path) {
             unlocked(p.mutex, [&] { fusion::save_volume(path, p.pipeline->map(), &p.pipeline->store()); });
           },
           py::arg("path"),
           "writes the map (the TSDF volume, resident and streamed-out blocks; no keyframes) atomically, in "
           "the format of `hashfusion run --save-map`")
      .def("load",
           [](Pipeline& p, const std::string& path) {
             require_existing_path(path, "Pipeline.load");
             unlocked(p.mutex, [&] {
               fusion::Volume v = fusion::load_volume(path);
               p.pipeline->load_map(std::move(v.grid), std::move(v.store));
             });
           },
           py::arg("path"),
           "before the first frame: continue in a saved map (`run --load-map`): the first frame is placed at its "
           "ground-truth pose, else at the map's origin; the configuration's voxel size must be the map's")
      .def("extract_mesh",
           [](Pipeline& p) { return unlocked(p.mutex, [&] { return p.pipeline->extract_mesh(); }); })
      .def("extract_cloud",
           [](Pipeline& p) {
             return unlocked(p.mutex, [&] { return slam::surface_cloud(p.pipeline->extract_mesh()); });
           },
           "the surface as a PointCloud: the mesh's vertices with colour and normals (what `run --save-cloud` "
           "writes)")
      .def("render",
           [](Pipeline& p, const py::object& pose) {
             const SE3 T = se3_from_array(pose, "T_world_camera");
             ColorImage image = unlocked(p.mutex, [&] { return p.pipeline->render(T); });
             return color_to_array(std::move(image));
           },
           py::arg("T_world_camera"), "shaded raycast of the model, uint8 (H, W, 3)")
      .def("corrected_trajectory",
           [](Pipeline& p) {
             const Trajectory t = unlocked(p.mutex, [&] { return p.pipeline->corrected_stamped_trajectory(); });
             return trajectory_to_python(t);
           },
           "(stamps (N,), poses (N, 4, 4)): every processed frame's pose after the loop closures so far, with its "
           "time stamp, as hf.ate / hf.evaluate take it")
      .def_property_readonly("config", [](Pipeline& p) { return json_to_python(slam::config_to_json(p.pipeline->config())); })
      .def_property_readonly("camera", [](Pipeline& p) { return p.pipeline->camera(); })
      .def_property_readonly("frames_processed", [](Pipeline& p) { return p.pipeline->frames_processed(); })
      .def_property_readonly("frames_lost", [](Pipeline& p) { return p.pipeline->frames_lost(); });
  m.def("default_config", [] { return json_to_python(slam::config_to_json(slam::PipelineConfig{})); },
        "the pipeline's defaults as a config dict");
}

void bind_registration(py::module_& m) {
  py::class_<Registration>(m, "Registration")
      .def_property_readonly("name", [](const Registration& r) { return r.registration->name(); })
      .def("align",
           [](Registration& r, const RgbdFrame& current, const RgbdFrame& reference, const PinholeCamera& camera,
              const py::object& guess, const py::object& levels) {
             const SE3 T_guess = guess.is_none() ? SE3() : se3_from_array(guess, "T_ref_cur_initial");
             FramePyramidOptions o;
             // By default as many levels as the method's iterations use (combined's defaults: 5).
             o.levels = levels.is_none() ? int(r.registration->options().driver.iterations.size()) : levels.cast<int>();
             return unlocked(r.mutex, [&] {
               const FramePyramid cur = build_frame_pyramid(current.depth, &current.color, camera, o);
               const FramePyramid ref = build_frame_pyramid(reference.depth, &reference.color, camera, o);
               return r.registration->align(cur, ref, T_guess);
             });
           },
           py::arg("current"), py::arg("reference"), py::arg("camera"), py::arg("T_ref_cur_initial") = py::none(),
           py::arg("levels") = py::none(),
           "T_ref_cur maps current-camera points into the reference camera; levels: the pyramid's, by default as "
           "many as the method's iterations list");
  m.def("make_registration",
        [](const std::string& name, const py::object& options, const std::string& backend) {
          auto r = std::make_unique<Registration>();
          if (options.is_none()) {
            r->registration = make_registration(name, backend);
          } else {
            const nlohmann::json j = json_from_python(options, "options");
            if (!j.is_object()) throw ValueError("options: expected a dict of the method's option keys");
            const RegistrationOptions o = slam::registration_options_from_json(name, j, "options");
            r->registration = make_registration(name, o, make_backend(backend));
          }
          return r;
        },
        py::arg("name"), py::arg("options") = py::none(), py::arg("backend") = "cpu",
        "a registry method; options: a dict of its keys (report.json's \"registration_options\" for that "
        "method) over the method's defaults; unknown keys and bad values raise hf.Error naming them");
  m.def("registration_options",
        [](const std::string& name) {
          RegistrationOptions o = default_registration_options(name);
          return json_to_python(slam::config_to_json([&] {
                                  slam::PipelineConfig c;
                                  c.registration = name;
                                  c.registration_options = o;
                                  return c;
                                }())["registration_options"]);
        },
        py::arg("name"), "a method's default options as the dict make_registration(name, options=) takes");
  m.def("registration_names", &registration_names);
}

void bind_eval(py::module_& m) {
  m.def("evaluate",
        [](const py::object& gt, const py::object& est, double max_difference_s, double offset_s, double delta_s) {
          const Trajectory g = trajectory_from_python(gt, "gt"), e = trajectory_from_python(est, "est");
          return json_to_python(metrics_to_json(
              evaluate_trajectory(g, e, {.max_difference_s = max_difference_s, .offset_s = offset_s,
                                         .rpe_delta_s = delta_s})
                  .metrics()));
        },
        py::arg("gt"), py::arg("est"), py::arg("max_difference_s") = 0.02, py::arg("offset_s") = 0.0,
        py::arg("delta_s") = 1.0, "the metrics of `hashfusion eval --json` (trajectories: path or (stamps, poses))");
  m.def("ate",
        [](const py::object& gt, const py::object& est, double max_difference_s, double offset_s) {
          const Trajectory g = trajectory_from_python(gt, "gt"), e = trajectory_from_python(est, "est");
          const AteResult ate =
              evaluate_ate(g, e, {.max_difference_s = max_difference_s, .offset_s = offset_s});
          TrajectoryMetrics metrics;
          metrics.pairs = ate.pairs.size();
          metrics.ate_m = ate.error_m;
          return ate_dict(ate, metrics_to_json(metrics));
        },
        py::arg("gt"), py::arg("est"), py::arg("max_difference_s") = 0.02, py::arg("offset_s") = 0.0,
        "absolute trajectory error (evaluate_ate.py): ate_* statistics, T_gt_est, errors_m per pair");
  m.def("rpe",
        [](const py::object& gt, const py::object& est, double delta_s, double offset_s) {
          const Trajectory g = trajectory_from_python(gt, "gt"), e = trajectory_from_python(est, "est");
          const RpeResult rpe = evaluate_rpe(g, e, {.delta_s = delta_s, .offset_s = offset_s});
          TrajectoryMetrics metrics;
          metrics.rpe_pairs = rpe.pairs.size();
          metrics.rpe_delta_s = rpe.delta_s;
          if (!rpe.empty()) metrics.rpe_trans_m_per_s = rpe.trans_m_per_s, metrics.rpe_rot_deg_per_s = rpe.rot_deg_per_s;
          return rpe_dict(rpe, metrics_to_json(metrics));
        },
        py::arg("gt"), py::arg("est"), py::arg("delta_s") = 1.0, py::arg("offset_s") = 0.0,
        "relative pose error per second (evaluate_rpe.py --fixed_delta): rpe_* statistics and per-pair values");
}

}  // namespace

void bind_slam(py::module_& m) {
  bind_dataset(m);
  bind_results(m);
  bind_pipeline(m);
  bind_registration(m);
  bind_eval(m);
}

}  // namespace hf::python
