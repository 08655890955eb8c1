// `tpb reference` (reference.cpp), and what `tpb converge` shares with it.
#pragma once
#include "eval/reference.h"

#include <string>

namespace tpb::app {

// One line (two with its self-error) describing a reference file, as `tpb reference` prints it.
void printReference(const std::string& path, const ReferenceInfo& info);

}  // namespace tpb::app
