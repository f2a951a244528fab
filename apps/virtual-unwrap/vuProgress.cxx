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
#include "vuProgress.h"

#include <algorithm>

#include "vuOutput.h"

#include "itkCommand.h"

#include <unistd.h>

#include <iomanip>
#include <iostream>

namespace vu {
Progress::Progress(bool quiet, bool json)
  : m_Quiet(quiet)
  , m_Json(json)
  , m_Terminal(isatty(STDERR_FILENO) != 0)
{}

void
Progress::Start(const std::string & stage, const std::string & message)
{
  m_Stage = stage;
  m_LastPercent = -1;
  SetActivity(message);
  if (m_Quiet)
  {
    return;
  }
  if (m_Json)
  {
    std::cerr << nlohmann::json{ { "event", "start" }, { "stage", stage }, { "message", message } }.dump() << std::endl;
  }
  else
  {
    std::cerr << "[" << stage << "] " << message << std::endl;
  }
}

void
Progress::Bar(double fraction)
{
  const int percent = static_cast<int>(fraction * 100.0);
  if (m_Quiet || percent == m_LastPercent)
  {
    return;
  }
  m_LastPercent = percent;
  if (m_Json)
  {
    if (percent % 10 == 0)
    {
      std::cerr << nlohmann::json{ { "event", "progress" }, { "stage", m_Stage }, { "percent", percent } }.dump()
                << std::endl;
    }
    return;
  }
  if (!m_Terminal)
  {
    return;
  }
  const int width = 40, filled = width * percent / 100;
  std::cerr << "\r  " << std::string(filled, '#') << std::string(width - filled, '.') << ' ' << std::setw(3) << percent
            << "%" << std::flush;
}

void
Progress::Observe(itk::ProcessObject * filter)
{
  auto observer = itk::CStyleCommand::New();
  observer->SetClientData(this);
  observer->SetConstCallback([](const itk::Object * caller, const itk::EventObject &, void * self) {
    static_cast<Progress *>(self)->Bar(static_cast<const itk::ProcessObject *>(caller)->GetProgress());
  });
  filter->AddObserver(itk::ProgressEvent(), observer);
}

void
Progress::Tick(const std::string & phase, uint64_t step)
{
  if (m_Quiet || step % 50 != 0)
  {
    return;
  }
  if (m_Json)
  {
    std::cerr << nlohmann::json{
      { "event", "step" }, { "stage", m_Stage }, { "phase", phase }, { "step", step }
    }.dump() << std::endl;
  }
  else if (m_Terminal)
  {
    std::cerr << "\r  " << phase << ": step " << step << "        " << std::flush;
  }
}

void
Progress::Done(const std::string & stage, double seconds)
{
  if (m_Quiet)
  {
    return;
  }
  if (m_Json)
  {
    std::cerr << nlohmann::json{ { "event", "done" }, { "stage", stage }, { "seconds", seconds } }.dump() << std::endl;
    return;
  }
  if (m_Terminal)
  {
    std::cerr << "\r" << std::string(60, ' ') << "\r";
  }
  std::cerr << "[" << stage << "] done in " << std::fixed << std::setprecision(2) << seconds << " s" << std::endl;
}

void
Progress::Finish(const std::string & outputDirectory, const nlohmann::json & report)
{
  if (m_Quiet)
  {
    return;
  }
  auto legibility = [](const nlohmann::json & l) {
    std::cout << "texture NCC " << l["texture_ncc"].get<double>() << ", ";
    if (l["character_error_rate"].is_number())
    {
      std::cout << "OCR character error rate " << l["character_error_rate"].get<double>() << std::endl;
    }
    else
    {
      std::cout << "no OCR (" << l.value("ocr_error", std::string("not run")) << ")" << std::endl;
    }
  };
  const bool folders = report.contains("sheets") &&
                       std::any_of(report["sheets"].begin(), report["sheets"].end(), [](const nlohmann::json & sheet) {
                         return sheet.contains("folder");
                       });
  if (!folders)
  {
    std::cout << "results in " << outputDirectory << " (texture.png, flat.obj, preview.png, report.json)" << std::endl;
    if (report.contains("legibility"))
    {
      legibility(report["legibility"]);
    }
    return;
  }
  std::cout << "results in " << outputDirectory << ": " << report["sheets"].size()
            << " sheets found, each unwrapped in a folder of its own (texture.png, flat.obj, preview.png, "
               "report.json); the list in "
               "report.json"
            << std::endl;
  for (const auto & sheet : report["sheets"])
  {
    if (sheet.contains("folder"))
    {
      std::cout << "  " << sheet["folder"].get<std::string>() << ": " << sheet["area_mm2"].get<double>() << " mm^2";
      if (sheet.contains("legibility"))
      {
        std::cout << ", ";
        legibility(sheet["legibility"]);
      }
      else
      {
        std::cout << std::endl;
      }
    }
  }
}
} // namespace vu
