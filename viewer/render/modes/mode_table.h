// The makers of the modes' passes, one per file, for the table in mode_table.cpp.
#pragma once

#include <memory>

#include "viewer/render/modes/mode_pass.h"

namespace vxl {

std::unique_ptr<ModePass> make_opaque_pass();
std::unique_ptr<ModePass> make_unsorted_pass();
std::unique_ptr<ModePass> make_additive_pass();
std::unique_ptr<ModePass> make_wboit_pass();
std::unique_ptr<ModePass> make_basic_pass();
std::unique_ptr<ModePass> make_axis_pass();
std::unique_ptr<ModePass> make_segsort_pass();
std::unique_ptr<ModePass> make_exact_pass();

}  // namespace vxl
