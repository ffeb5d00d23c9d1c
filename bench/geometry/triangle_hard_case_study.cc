// Counts, on the hard-case suite (tests/far/geometry/hard_cases.h), how often FCL 0.7's
// triangle test fcl::detail::Intersect<double>::intersect_Triangle and far::TrianglesIntersect
// disagree with the exact rational answer, per family, over every case and all 72 relabelings
// (vertex orders of both triangles, and the swap). Prints a Markdown table for
// bench/RESULTS.md; with a path argument also writes the per-case counts as CSV.
//   far_triangle_hard_case_study [cases.csv]

#include <cstdio>
#include <fstream>
#include <map>
#include <string>

#include "hard_cases.h"
#include <fcl/narrowphase/detail/traversal/collision/intersect.h>

#include "far/geometry/triangle_tests.h"

namespace {

struct Tally {
  int cases = 0;
  int cases_fcl_wrong = 0;  // cases where FCL is wrong for at least one relabeling
  long tests = 0;
  long fcl_false_positive = 0;  // FCL says "intersect", exact says disjoint
  long fcl_false_negative = 0;  // FCL misses a contact
  long far_wrong = 0;
};

bool Fcl(const far::TrianglePoints& s, const far::TrianglePoints& t) {
  return fcl::detail::Intersect<double>::intersect_Triangle(s.a, s.b, s.c, t.a, t.b, t.c);
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<far::reference::HardCase> cases = far::reference::MakeHardCases();
  std::map<std::string, Tally> by_family;
  Tally total;
  std::ofstream csv;
  if (argc > 1) {
    csv.open(argv[1]);
    csv << "name,category,exact,fcl_wrong_of_72,far_wrong_of_72\n";
  }
  for (const far::reference::HardCase& c : cases) {
    int fcl_wrong = 0;
    int far_wrong = 0;
    Tally& family = by_family[c.category];
    for (const auto& [s, t] : far::reference::Relabelings(c.s, c.t)) {
      const bool fcl = Fcl(s, t);
      if (fcl != c.intersect) {
        ++fcl_wrong;
        (fcl ? family.fcl_false_positive : family.fcl_false_negative) += 1;
        (fcl ? total.fcl_false_positive : total.fcl_false_negative) += 1;
      }
      far_wrong += far::TrianglesIntersect(s, t) != c.intersect;
    }
    for (Tally* tally : {&family, &total}) {
      tally->cases += 1;
      tally->cases_fcl_wrong += fcl_wrong > 0;
      tally->tests += 72;
      tally->far_wrong += far_wrong;
    }
    if (csv) {
      csv << c.name << ',' << c.category << ',' << c.intersect << ',' << fcl_wrong << ','
          << far_wrong << '\n';
    }
  }
  std::printf(
      "| family | cases | tests (x72) | FCL wrong cases | FCL false pos. | FCL false neg. "
      "| far wrong |\n|---|---:|---:|---:|---:|---:|---:|\n");
  const auto row = [](const std::string& name, const Tally& t) {
    std::printf("| %s | %d | %ld | %d | %ld | %ld | %ld |\n", name.c_str(), t.cases, t.tests,
                t.cases_fcl_wrong, t.fcl_false_positive, t.fcl_false_negative, t.far_wrong);
  };
  for (const auto& [name, tally] : by_family) row(name, tally);
  row("**all**", total);
  return total.far_wrong == 0 ? 0 : 1;
}
