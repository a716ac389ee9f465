// SPDX-License-Identifier: BSD-3-Clause
#include "DisplayDefaults.h"

#include "MDBlocks.h"

#include <vtkSMSettings.h>

void MuscleDeformationRegisterDisplayDefaults()
{
  // Priority 0, as ParaView's own standard presets: below site and user settings.
  vtkSMSettings::GetInstance()->AddCollectionFromString(mdvtk::DefaultDisplaySettings(), 0.0);
}
