// The parts of the `hashfusion` module bound outside module.cpp.
#pragma once

#include <pybind11/pybind11.h>

namespace hf::python {

// Datasets, the pipeline and its results, registration, evaluation (bind_slam.cpp).
void bind_slam(pybind11::module_& m);
// Head features and curvature (bind_head.cpp), LiDAR built-up areas (bind_lidar.cpp), DLT triangulation
// (bind_photogrammetry.cpp).
void bind_head(pybind11::module_& m);
void bind_lidar(pybind11::module_& m);
void bind_photogrammetry(pybind11::module_& m);

}  // namespace hf::python
