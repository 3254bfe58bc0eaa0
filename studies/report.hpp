#pragma once
// The family's report fields (cases/spline_space.hpp) in the commands' JSON and text output.
#include <string>
#include <vector>

#include "cases/json_output.hpp"
#include "cases/spline_space.hpp"
#include "solver/poisson_solver.hpp"

namespace knotwork {

// The condition estimates of a solve made with estimate_condition, as fields: JSON
// condition.stiffness / condition.mass (null when not estimated: condition.failure says why),
// a text line, and two columns of converge's table.
std::vector<ReportField> condition_fields(const PoissonSolution& s);
// Adds the fields to a JSON object ("a.b" keys become member b of object a).
void add_fields(Json& object, const std::vector<ReportField>& fields);
// Prints the fields that have a text line, as "  label    text" (label padded to `width`).
void print_field_lines(const std::vector<ReportField>& fields, int width = 8);
// The value of a numeric field as a double (NaN for null, text or lists).
double field_number(const ReportField& field);
// The field with this key, or null.
const ReportField* find_field(const std::vector<ReportField>& fields, const std::string& key);
// A convergence rate as the tables print it ("-" for NaN, else two decimals).
std::string rate_text(double rate);
// A field's value as CSV text ("" for null; lists joined by ';').
std::string field_csv(const ReportField& field);

}  // namespace knotwork
