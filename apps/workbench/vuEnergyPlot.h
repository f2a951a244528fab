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
#ifndef vuEnergyPlot_h
#define vuEnergyPlot_h

#include <QWidget>

#include <cstdint>
#include <vector>

namespace vu {
/** The simulation's kinetic and spring energy against the step, on a log scale. */
class EnergyPlot : public QWidget
{
public:
  explicit EnergyPlot(QWidget * parent = nullptr);
  void
  Add(uint64_t step, double kinetic, double spring);
  void
  Clear();
  size_t
  GetNumberOfSamples() const
  {
    return m_Steps.size();
  }
  QSize
  sizeHint() const override
  {
    return { 360, 160 };
  }

protected:
  void
  paintEvent(QPaintEvent * event) override;

private:
  std::vector<double> m_Steps, m_Kinetic, m_Spring;
};
} // namespace vu

#endif
