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
// virtual-unwrap: the module's command-line tool. Each subcommand lives in its own
// vuCommand*.cxx; this file only dispatches and turns failures into one-line errors.
#include "vuCommands.h"

#include "vuOutput.h"

#include "itkMacro.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include <sys/resource.h>
#if defined(__GLIBC__)
#  include <malloc.h>
#endif

namespace {
// ITK's exception text spans several lines (location, file, description): keep the
// description, which says what went wrong.
// An allocation that failed cannot say how much it wanted: say what was being done and
// what limits the memory.
std::string
OutOfMemory()
{
  std::string text = "out of memory";
  if (!vu::GetActivity().empty())
  {
    text += " while " + vu::GetActivity();
  }
  struct rlimit limit
  {};
  if (getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
  {
    text += " (the address-space limit, ulimit -v, is " + vu::DescribeBytes(limit.rlim_cur) + ")";
  }
  else
  {
    text += " (a smaller --roi or a --shrink factor needs less)";
  }
  return text;
}
} // namespace

int
main(int argc, char * argv[])
{
#if defined(__GLIBC__)
  // Every stage allocates and frees image-sized buffers of a few MiB: keep freed memory up to
  // 128 MiB for reuse instead of handing it back to the system and faulting it in again
  // (buffers above 32 MiB, the scan and its masks, are still mapped and returned on their own).
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 128 << 20);
#endif
  CLI::App app{ "virtual-unwrap: read a CT scan of a rolled or folded document, find the writing surface, "
                "unroll and flatten it by mass-spring simulation, and render a flat, readable image.",
                "virtual-unwrap" };
  app.set_version_flag("--version", "virtual-unwrap 0.1.0 (VirtualUnwrapping ITK module)");
  app.require_subcommand(1);
  app.get_formatter()->column_width(42);
  vu::RegisterUnwrapCommand(app);
  vu::RegisterDistortionCommand(app);
  vu::RegisterFlattenCommand(app);
  vu::RegisterPhantomCommand(app);
  vu::RegisterInfoCommand(app);
  vu::RegisterSegmentCommand(app);

  try
  {
    app.parse(argc, argv);
  }
  catch (const CLI::Success & e) // --help, --version
  {
    return app.exit(e);
  }
  catch (const CLI::ParseError & e)
  {
    // One line like every other error (CLI11's own report adds a second).
    std::cerr << "virtual-unwrap: error: " << vu::OneLine(e.what()) << " (see virtual-unwrap --help)" << std::endl;
    return 2;
  }
  catch (const itk::MemoryAllocationError &)
  {
    std::cerr << "virtual-unwrap: error: " << OutOfMemory() << std::endl;
    return 1;
  }
  catch (const std::bad_alloc &)
  {
    std::cerr << "virtual-unwrap: error: " << OutOfMemory() << std::endl;
    return 1;
  }
  catch (const itk::ExceptionObject & e)
  {
    std::cerr << "virtual-unwrap: error: " << vu::OneLine(e.GetDescription()) << std::endl;
    return 1;
  }
  catch (const std::exception & e)
  {
    std::cerr << "virtual-unwrap: error: " << vu::OneLine(e.what()) << std::endl;
    return 1;
  }
  return 0;
}
