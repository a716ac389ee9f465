// SPDX-License-Identifier: BSD-3-Clause
// Run by ParaView when it loads the plugin (paraview_add_plugin INITIALIZERS).
#pragma once

/// Registers the plugin's display defaults (mdvtk::DefaultDisplaySettings) as settings of the
/// lowest priority: bones, muscles and action lines then show in their colours, and action lines
/// as tubes, in the GUI and in pvpython; a user's own saved settings still win.
void MuscleDeformationRegisterDisplayDefaults();
