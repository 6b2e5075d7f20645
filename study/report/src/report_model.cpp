// The report's analysis beyond ranks: the mixed model on log lap times and
// the laps against the track's reference lap.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "haptel/config/track.hpp"
#include "haptel/core/json.hpp"
#include "haptel/study/report.hpp"

namespace haptel::study {
namespace {

std::string Fixed(double value, int decimals) {
  if (!std::isfinite(value)) return "-";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}

/// With its sign, "+0.197" or "-0.021" (built piecewise: GCC 12 warns
/// falsely, -Wrestrict, on "literal" + string).
std::string Signed(double value, int decimals) {
  std::string text(value >= 0.0 ? "+" : "");
  text += Fixed(value, decimals);
  return text;
}

/// A p-value as a paper prints it: "= 0.0062", or "< 0.0001".
std::string PText(double p) { return p < 1e-4 ? "< 0.0001" : Fixed(p, 4); }
std::string PClause(double p) { return p < 1e-4 ? "p < 0.0001" : "p = " + Fixed(p, 4); }

std::string Padded(const std::string& text, size_t width) {
  return text.size() >= width ? text + " " : text + std::string(width - text.size(), ' ');
}

std::string Number(double v) { return std::isfinite(v) ? JsonNumber(v) : std::string("null"); }

std::string ContrastJson(const MixedModelContrast& c) {
  return "\"estimate\":" + Number(c.estimate) + ",\"se\":" + Number(c.standard_error) +
         ",\"df\":" + Number(c.degrees_of_freedom) + ",\"t\":" + Number(c.t) +
         ",\"ci_low\":" + Number(c.ci_low) + ",\"ci_high\":" + Number(c.ci_high) +
         ",\"p\":" + Number(c.p_value);
}

constexpr const char* kModel = "log(lap time) ~ condition + position + (1 | participant)";

}  // namespace

double PercentOverReference(double lap_time_s, double reference_lap_s) {
  return 100.0 * (lap_time_s - reference_lap_s) / reference_lap_s;
}

void FitLapTimeModel(const StudyResults& results, StudyReport& report) {
  std::vector<MixedModelObservation> observations;
  for (const StudyResults::Trial& t : results.trials) {
    const auto p =
        std::find(results.participants.begin(), results.participants.end(), t.participant);
    const auto c = std::find(results.conditions.begin(), results.conditions.end(), t.condition);
    if (p == results.participants.end() || c == results.conditions.end()) continue;
    if (!(t.lap_time_s > 0.0)) {
      report.why_no_mixed_model = "no mixed model: " + t.participant + "'s trial " +
                                  std::to_string(t.position) + " has lap time " +
                                  Fixed(t.lap_time_s, 3) + " s; log(lap time) needs more than 0";
      return;
    }
    observations.push_back({static_cast<int>(p - results.participants.begin()),
                            static_cast<int>(c - results.conditions.begin()),
                            static_cast<double>(t.position), std::log(t.lap_time_s)});
  }
  try {
    report.mixed_model =
        FitMixedModel(observations, static_cast<int>(results.conditions.size()), 0);
  } catch (const std::invalid_argument& e) {
    report.why_no_mixed_model = std::string("no mixed model: ") + e.what();
  }
}

void ReadBaseline(const std::filesystem::path& study_file, const std::string& definition_form,
                  StudyResults& results) {
  std::string track;
  std::istringstream lines(definition_form);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("track: ", 0) == 0) track = line.substr(7);
  }
  if (track.empty() || track == "(none)") {
    results.baseline_note = "no baseline: the study names no track";
    return;
  }
  // As the definition form writes it: relative to the study file's folder.
  const std::filesystem::path path(track);
  results.track_file =
      path.is_absolute() ? path : (study_file.parent_path() / path).lexically_normal();
  try {
    const TrackConfig config = LoadTrack(results.track_file);
    results.reference_lap_s = config.reference_lap_s;
    if (!results.reference_lap_s) {
      results.baseline_note =
          "no baseline: " + results.track_file.string() + " gives no reference_lap_s";
    }
  } catch (const std::exception& e) {
    results.baseline_note = std::string("no baseline: ") + e.what();
  }
}

std::string FormatLapTimeModel(const StudyResults& results, const StudyReport& report) {
  std::ostringstream o;
  if (!report.mixed_model) {
    o << "  " << report.why_no_mixed_model << "\n";
    return o.str();
  }
  const MixedModelResult& m = *report.mixed_model;
  o << "  mixed model: " << kModel << ", " << m.observations << " trials of " << m.participants
    << " participants\n"
    << "    clock: the lap clock (lap time as scored, from the start line; an unfinished lap at "
       "the "
    << Fixed(results.trial_cap_s, 0) << " s cap)\n"
    << "    scale: log, so an estimate is a log ratio against "
    << results.conditions[static_cast<size_t>(m.reference_condition)]
    << " and exp(estimate) its ratio, \"x lap time\"\n"
    << "    method: " << m.method << "\n";
  o << "    " << Padded("condition", 22) << Padded("estimate", 10) << Padded("SE", 8)
    << Padded("df", 7) << Padded("95 % CI", 20) << Padded("p", 10) << "x lap time (95 % CI)\n";
  for (size_t c = 0; c < m.conditions.size(); ++c) {
    const MixedModelCondition& condition = m.conditions[c];
    o << "    " << Padded(results.conditions[c], 22);
    if (condition.reference) {
      o << "reference\n";
    } else if (!condition.effect) {
      o << "no trials\n";
    } else {
      const MixedModelContrast& e = *condition.effect;
      o << Padded(Signed(e.estimate, 3), 10) << Padded(Fixed(e.standard_error, 3), 8)
        << Padded(Fixed(e.degrees_of_freedom, 1), 7)
        << Padded("[" + Signed(e.ci_low, 3) + ", " + Signed(e.ci_high, 3) + "]", 20)
        << Padded(PText(e.p_value), 10) << Fixed(std::exp(e.estimate), 2) << " ("
        << Fixed(std::exp(e.ci_low), 2) << "-" << Fixed(std::exp(e.ci_high), 2) << ")\n";
    }
  }
  if (m.position) {
    const MixedModelContrast& e = *m.position;
    o << "    " << Padded("position (per trial)", 22) << Padded(Signed(e.estimate, 3), 10)
      << Padded(Fixed(e.standard_error, 3), 8) << Padded(Fixed(e.degrees_of_freedom, 1), 7)
      << Padded("[" + Signed(e.ci_low, 3) + ", " + Signed(e.ci_high, 3) + "]", 20)
      << Padded(PText(e.p_value), 10) << Fixed(std::exp(e.estimate), 3) << " ("
      << Fixed(std::exp(e.ci_low), 3) << "-" << Fixed(std::exp(e.ci_high), 3)
      << ")  learning, linear in the trial's order\n";
  }
  const MixedModelConditionTest& test = m.condition_test;
  o << "    the condition as a whole: Satterthwaite's F = " << Fixed(test.f, 3) << " on "
    << test.degrees_of_freedom << " and " << Fixed(test.denominator_df, 1) << " df, "
    << PClause(test.p_value)
    << "; beside it the likelihood-ratio chi2 = " << Fixed(test.chi_square, 3)
    << ", df = " << test.degrees_of_freedom << ", " << PClause(test.likelihood_ratio_p_value)
    << " (ML refits; liberal with few participants)\n";
  o << "    variance: participants " << Fixed(m.participant_variance, 4) << " (SD "
    << Fixed(std::sqrt(m.participant_variance), 3) << "), residual "
    << Fixed(m.residual_variance, 4) << " (SD " << Fixed(std::sqrt(m.residual_variance), 3)
    << ") on the log scale" << (m.boundary ? "; boundary fit" : "") << "\n";
  o << "    estimated mean lap time at position " << Fixed(m.mean_position, 2)
    << " (exp of the log-scale mean: a geometric mean), s, 95 % CI:\n";
  for (size_t c = 0; c < m.conditions.size(); ++c) {
    if (!m.conditions[c].mean) continue;
    const MixedModelContrast& mean = *m.conditions[c].mean;
    o << "      " << Padded(results.conditions[c], 22) << Fixed(std::exp(mean.estimate), 2) << " ("
      << Fixed(std::exp(mean.ci_low), 2) << "-" << Fixed(std::exp(mean.ci_high), 2) << ")\n";
  }
  for (const std::string& note : m.notes) o << "    note: " << note << "\n";
  return o.str();
}

std::string FormatBaseline(const StudyResults& results, const StudyReport& report) {
  std::ostringstream o;
  if (!results.reference_lap_s) {
    o << "  " << results.baseline_note << "\n";
    return o.str();
  }
  const double reference = *results.reference_lap_s;
  o << "  baseline: reference lap " << Fixed(reference, 2) << " s (" << results.track_file.string()
    << "); each lap's percentage over it, per participant:\n    " << std::string(20, ' ');
  for (const std::string& p : results.participants)
    o << " " << std::string(std::max<int>(0, 8 - static_cast<int>(p.size())), ' ') << p;
  o << "     mean\n";
  for (const ConditionSummary& c : report.conditions) {
    o << "    " << Padded(c.name, 20);
    for (const double v : c.lap_time_s) {
      const std::string text =
          std::isfinite(v) ? Signed(PercentOverReference(v, reference), 0) + "%" : "-";
      o << " " << std::string(std::max(0, 8 - static_cast<int>(text.size())), ' ') << text;
    }
    o << "  "
      << (std::isfinite(c.mean_lap_time_s)
              ? Signed(PercentOverReference(c.mean_lap_time_s, reference), 1) + "%"
              : "-")
      << "\n";
  }
  return o.str();
}

std::string LapTimeModelJson(const StudyResults& results, const StudyReport& report) {
  if (!report.mixed_model)
    return "\"lmm\":null,\"why_no_lmm\":" + JsonString(report.why_no_mixed_model);
  const MixedModelResult& m = *report.mixed_model;
  std::string out = "\"lmm\":{\"model\":" + JsonString(kModel) +
                    ",\"clock\":\"lap\",\"scale\":\"log\"" + ",\"method\":" + JsonString(m.method) +
                    ",\"trials\":" + std::to_string(m.observations) +
                    ",\"participants\":" + std::to_string(m.participants) + ",\"reference\":" +
                    JsonString(results.conditions[static_cast<size_t>(m.reference_condition)]) +
                    ",\"mean_position\":" + Number(m.mean_position) + ",\"conditions\":[";
  for (size_t c = 0; c < m.conditions.size(); ++c) {
    const MixedModelCondition& condition = m.conditions[c];
    if (c > 0) out += ",";
    out += "{\"name\":" + JsonString(results.conditions[c]) +
           ",\"reference\":" + (condition.reference ? "true" : "false") +
           ",\"estimable\":" + (condition.estimable ? "true" : "false");
    if (condition.effect) {
      const MixedModelContrast& e = *condition.effect;
      out += "," + ContrastJson(e) + ",\"ratio\":" + Number(std::exp(e.estimate)) +
             ",\"ratio_ci_low\":" + Number(std::exp(e.ci_low)) +
             ",\"ratio_ci_high\":" + Number(std::exp(e.ci_high));
    } else {
      // The reference is the zero the others are measured from; a condition
      // without trials has no estimate.
      out += std::string(",\"estimate\":") + (condition.reference ? "0" : "null") +
             ",\"se\":null,\"df\":null,\"t\":null,\"ci_low\":null,\"ci_high\":null,\"p\":null,"
             "\"ratio\":" +
             (condition.reference ? "1" : "null") + ",\"ratio_ci_low\":null,\"ratio_ci_high\":null";
    }
    if (condition.mean) {
      out += ",\"mean_lap_time_s\":" + Number(std::exp(condition.mean->estimate)) +
             ",\"mean_ci_low_s\":" + Number(std::exp(condition.mean->ci_low)) +
             ",\"mean_ci_high_s\":" + Number(std::exp(condition.mean->ci_high));
    } else {
      out += ",\"mean_lap_time_s\":null,\"mean_ci_low_s\":null,\"mean_ci_high_s\":null";
    }
    out += "}";
  }
  out += "],\"position\":";
  if (m.position) {
    out += "{";
    out += ContrastJson(*m.position);
    out += "}";
  } else {
    out += "null";
  }
  out += ",\"condition_test\":{\"method\":\"Satterthwaite F\",\"f\":" + Number(m.condition_test.f) +
         ",\"df\":" + std::to_string(m.condition_test.degrees_of_freedom) +
         ",\"den_df\":" + Number(m.condition_test.denominator_df) +
         ",\"p\":" + Number(m.condition_test.p_value) +
         ",\"chi2\":" + Number(m.condition_test.chi_square) +
         ",\"lrt_p\":" + Number(m.condition_test.likelihood_ratio_p_value) + "}";
  out += ",\"variance\":{\"participant\":" + Number(m.participant_variance) +
         ",\"residual\":" + Number(m.residual_variance) +
         ",\"participant_sd\":" + Number(std::sqrt(m.participant_variance)) +
         ",\"residual_sd\":" + Number(std::sqrt(m.residual_variance)) +
         ",\"boundary\":" + (m.boundary ? "true" : "false") + "}";
  out += ",\"reml_criterion\":" + Number(m.reml_criterion) + ",\"notes\":[";
  for (size_t i = 0; i < m.notes.size(); ++i) {
    if (i > 0) out += ",";
    out += JsonString(m.notes[i]);
  }
  out += "]},\"why_no_lmm\":\"\"";
  return out;
}

std::string BaselineJson(const StudyResults& results, const StudyReport& report) {
  if (!results.reference_lap_s)
    return "\"baseline\":{\"reference_lap_s\":null,\"why\":" + JsonString(results.baseline_note) +
           "}";
  const double reference = *results.reference_lap_s;
  std::string out = "\"baseline\":{\"reference_lap_s\":" + Number(reference) +
                    ",\"track\":" + JsonString(results.track_file.string()) + ",\"laps\":[";
  bool first = true;
  for (const StudyResults::Trial& t : results.trials) {
    out += std::string(first ? "" : ",") + "{\"participant\":" + JsonString(t.participant) +
           ",\"condition\":" + JsonString(t.condition) +
           ",\"position\":" + std::to_string(t.position) +
           ",\"lap_time_s\":" + Number(t.lap_time_s) +
           ",\"over_reference_percent\":" + Number(PercentOverReference(t.lap_time_s, reference)) +
           "}";
    first = false;
  }
  out += "],\"conditions\":[";
  for (size_t i = 0; i < report.conditions.size(); ++i) {
    const ConditionSummary& c = report.conditions[i];
    out += std::string(i > 0 ? "," : "") + "{\"name\":" + JsonString(c.name) +
           ",\"mean_over_reference_percent\":" +
           Number(PercentOverReference(c.mean_lap_time_s, reference)) + "}";
  }
  return out + "]}";
}

}  // namespace haptel::study
