// The parts of the `hashfusion` module bound outside module.cpp.
#pragma once

#include <pybind11/pybind11.h>

namespace hf::python {

// Datasets, the pipeline and its results, registration, evaluation (bind_slam.cpp).
void bind_slam(pybind11::module_& m);

}  // namespace hf::python
