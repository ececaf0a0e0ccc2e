// The areas of the Python module, each bound in its own file.
#pragma once

#include <pybind11/pybind11.h>

namespace lfprobe::python {

void bind_render(pybind11::module_& m);
void bind_mesh(pybind11::module_& m); // meshes, Embree ground truth, mesh bakes, simulated scans
void bind_plan(pybind11::module_& m); // per-probe resolution, classification, planned bakes
void bind_staged_bake(pybind11::module_& m);    // cloud bakes in parts (a cluster's workers)
void bind_cloud_geometry(pybind11::module_& m); // a cloud's normals and spacing

} // namespace lfprobe::python
