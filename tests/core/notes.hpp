// phex tests — a triangulation's notes joined for INFO and find.
#pragma once
#include <string>

#include "phex/triangulation.hpp"

namespace phex::test {

// A triangulation's notes, one a line.
inline std::string allNotes(const Triangulation& triangulation) {
  std::string notes;
  for (const std::string& note : triangulation.notes) notes += note + "\n";
  return notes;
}

}  // namespace phex::test
