// testbench.render (python/src/render_python.cpp).
#pragma once
#include <pybind11/pybind11.h>

namespace tb::python {
void bind_render(pybind11::module_& m);
}
