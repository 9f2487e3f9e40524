// Placeholder replaced by the GUI implementation.
#include "app/commands.h"
#include "core/error.h"
namespace mesolab {
int run_gui(const GuiOptions&) { throw InputError("gui: not built yet"); }
}  // namespace mesolab
