#pragma once
// The identity of a trial: what the result store keys its results by (docs/results.md). A stored
// result is reused only when everything that can change it is the same: the build (version and
// commit), the trial's key (every plugin choice with its parameters, n, and its lap count when
// the study has a laps axis), the data files it reads (their SHA-256), the plugin modules its
// plugins come from (the SHA-256 of each .so, LoadedPlugin::sha256; built-in plugins add
// nothing: the commit covers them), and the study settings.
//
// The study settings are derived, not listed by hand: every field of StudyDefinition is read
// with Boost.PFR (field by field, nested aggregates included), so a field added to the study
// definition (or to the settings structs it holds) enters the identity by itself. Only the
// fields named in not_in_identity() stay out, each because it cannot change a trial's result
// (tests/run/test_trial_identity.cpp changes every field in turn and checks both directions).

#include <string>
#include <typeinfo>
#include <vector>

#include "rkhs/study/study.hpp"

namespace rkhs {

/// The study settings that can change a trial's result, as canonical text ("3=1:{3={0=25.13
/// ...}} 4={...} ..." by field position; the kind's own part as its alternative, the kind, and
/// its fields). Throws std::logic_error naming the field position when a
/// field has a type this function cannot write (a new kind of field: teach it, or exclude it
/// with its reason).
std::string study_settings_text(const StudyDefinition& study);

/// The fields of `study` left out of the identity (their addresses inside `study`, those of its
/// kind's own part included), with why.
struct ExcludedField {
  const void* address;
  const std::type_info* type;  ///< of the field (a struct's first field shares its address)
  const char* name;
  const char* reason;
};
std::vector<ExcludedField> not_in_identity(const StudyDefinition& study);

/// The content hash of each trial (SHA-256, hex): build, study settings, trial key, the
/// provenance of the data it reads and the content hash of every loaded plugin module one of
/// its plugins comes from (hashed once, when the module was loaded; not per trial). Equal hashes
/// mean the stored result can be reused.
std::vector<std::string> trial_hashes(const StudyDefinition& study,
                                      const std::vector<TrialSpec>& trials);

}  // namespace rkhs
