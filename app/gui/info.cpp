// mesolab info: what the library reports (info_fields, app/api.h) and the window's own libraries.
#include "app/api.h"
#include "app/commands.h"

#include <GLFW/glfw3.h>
#include <imgui.h>

#include <cstdio>
#include <string>

namespace mesolab {
int run_info() {
    auto fields = info_fields();
    int maj = 0, min = 0, rev = 0;
    glfwGetVersion(&maj, &min, &rev);
    fields.emplace_back("glfw", std::to_string(maj) + "." + std::to_string(min) + "." + std::to_string(rev));
    fields.emplace_back("imgui", IMGUI_VERSION);
    for (const auto& [name, value] : fields) {
        if (name == "version") std::printf("mesolab %s\n", value.c_str());
        else std::printf("%-17s %s\n", name.c_str(), value.c_str());
    }
    return 0;
}
}  // namespace mesolab
