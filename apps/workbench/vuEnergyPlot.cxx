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
#include "vuEnergyPlot.h"

#include <QPainter>
#include <QPainterPath>

#include <algorithm>
#include <cmath>

namespace vu {
EnergyPlot::EnergyPlot(QWidget * parent)
  : QWidget(parent)
{
  setMinimumHeight(110);
}

void
EnergyPlot::Add(uint64_t step, double kinetic, double spring)
{
  if (!m_Steps.empty() && static_cast<double>(step) < m_Steps.back())
  {
    Clear();
  }
  m_Steps.push_back(static_cast<double>(step));
  m_Kinetic.push_back(kinetic);
  m_Spring.push_back(spring);
  // Kept to a few thousand points: every other sample dropped when full.
  if (m_Steps.size() > 4000)
  {
    for (auto * series : { &m_Steps, &m_Kinetic, &m_Spring })
    {
      std::vector<double> kept;
      for (size_t i = 0; i < series->size(); i += 2)
      {
        kept.push_back((*series)[i]);
      }
      *series = std::move(kept);
    }
  }
  update();
}

void
EnergyPlot::Clear()
{
  m_Steps.clear();
  m_Kinetic.clear();
  m_Spring.clear();
  update();
}

void
EnergyPlot::paintEvent(QPaintEvent *)
{
  QPainter painter(this);
  painter.fillRect(rect(), QColor(250, 250, 250));
  const QRectF area = QRectF(rect()).adjusted(46, 8, -8, -22);
  painter.setPen(QColor(120, 120, 120));
  painter.drawRect(area);
  painter.drawText(QRectF(area.left(), area.bottom() + 2, area.width(), 18), Qt::AlignCenter, "step");
  if (m_Steps.size() < 2)
  {
    painter.drawText(area, Qt::AlignCenter, "energy: no simulation yet");
    return;
  }
  double lo = INFINITY, hi = -INFINITY;
  for (const auto * series : { &m_Kinetic, &m_Spring })
  {
    for (double v : *series)
    {
      if (v > 0.0 && std::isfinite(v))
      {
        lo = std::min(lo, std::log10(v));
        hi = std::max(hi, std::log10(v));
      }
    }
  }
  if (!std::isfinite(lo))
  {
    return;
  }
  hi = std::max(hi, lo + 1.0);
  const double first = m_Steps.front(), last = std::max(m_Steps.back(), first + 1.0);
  auto         point = [&](double step, double value) {
    const double y = value > 0.0 ? (std::log10(value) - lo) / (hi - lo) : 0.0;
    return QPointF(area.left() + area.width() * (step - first) / (last - first), area.bottom() - area.height() * y);
  };
  const std::pair<const std::vector<double> *, QColor> series[] = { { &m_Kinetic, QColor(200, 60, 40) },
                                                                    { &m_Spring, QColor(40, 90, 200) } };
  for (const auto & s : series)
  {
    QPainterPath path(point(m_Steps[0], (*s.first)[0]));
    for (size_t i = 1; i < m_Steps.size(); ++i)
    {
      path.lineTo(point(m_Steps[i], (*s.first)[i]));
    }
    painter.setPen(QPen(s.second, 1.5));
    painter.drawPath(path);
  }
  painter.setPen(Qt::black);
  painter.drawText(QRectF(0, area.top(), 44, 16), Qt::AlignRight, QString("1e%1").arg(std::ceil(hi)));
  painter.drawText(QRectF(0, area.bottom() - 16, 44, 16), Qt::AlignRight, QString("1e%1").arg(std::floor(lo)));
  painter.setPen(QColor(200, 60, 40));
  painter.drawText(QPointF(area.left() + 6, area.top() + 14), "kinetic");
  painter.setPen(QColor(40, 90, 200));
  painter.drawText(QPointF(area.left() + 66, area.top() + 14), "spring");
}
} // namespace vu
