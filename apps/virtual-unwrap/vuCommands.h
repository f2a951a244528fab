/*=========================================================================
 *
 *  Copyright NumFOCUS
 *
 *  Licensed under the Apache License, Version 2.0 (the "License");
 *  you may not use this file except in compliance with the License.
 *  You may obtain a copy of the License at
 *
 *         http://www.apache.org/licenses/LICENSE-2.0.txt
 *
 *  Unless required by applicable law or agreed to in writing, software
 *  distributed under the License is distributed on an "AS IS" BASIS,
 *  WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
 *  See the License for the specific language governing permissions and
 *  limitations under the License.
 *
 *=========================================================================*/
#ifndef vuCommands_h
#define vuCommands_h

#include "vuOutput.h"

#include "itkSheetMidSurfaceExtractor.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <stdexcept>
#include <string>

namespace vu {
/** A failure the user can act on: printed as one line, exit code 1. */
/** Option checks with messages a user reads (CLI11's own ranges print the largest double
 * in full): the value must be a finite number >= 0 (NonNegative) or > 0 (Positive). */
inline CLI::Validator
NumberCheck(bool zeroAllowed)
{
  return CLI::Validator(
    [zeroAllowed](std::string & value) -> std::string {
      double number = 0.0;
      if (!CLI::detail::lexical_cast(value, number) || !std::isfinite(number) || number < 0.0 ||
          (!zeroAllowed && number == 0.0))
      {
        return std::string("must be a number ") + (zeroAllowed ? ">= 0" : "> 0") + ", not " + value;
      }
      return {};
    },
    zeroAllowed ? "NONNEGATIVE" : "POSITIVE");
}
inline CLI::Validator
NonNegative()
{
  return NumberCheck(true);
}
inline CLI::Validator
Positive()
{
  return NumberCheck(false);
}

class UsageError : public std::runtime_error
{
public:
  using std::runtime_error::runtime_error;
};

/** Each subcommand adds itself to the application; its callback does the work and
 * throws (itk::ExceptionObject, vu::UsageError or std::exception) on failure. */
void
RegisterDistortionCommand(CLI::App & app);
void
RegisterFlattenCommand(CLI::App & app);
void
RegisterPhantomCommand(CLI::App & app);
void
RegisterInfoCommand(CLI::App & app);
void
RegisterSegmentCommand(CLI::App & app);
void
RegisterUnwrapCommand(CLI::App & app);

/** "auto" (returns false, `value` untouched) or a finite number (returns true); throws
 * UsageError naming `option` for anything else. */
bool
ParseAutoOrNumber(const std::string & text, const std::string & option, double & value);

/** The mesh spacing of `segment` and `unwrap`: "auto" (returns false), "MM" (both directions) or
 * "S,W" (along the sheet, along the roll axis). Throws UsageError for anything else or
 * a spacing that is not positive. */
bool
ParseMeshSpacing(const std::string & text, double spacing[2]);

/** How well the sheet was traced, for segment.json and report.json: method, turns, turn
 * spacing, interpolated slices, mean confidence, the runs of slices traced with low
 * confidence and the possible layer jumps. */
nlohmann::json
TraceJson(const itk::SheetMidSurfaceReport & report);
} // namespace vu

#endif
