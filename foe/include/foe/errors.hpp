#pragma once
// FoE opcodes, error codes and their texts: the FoE vocabulary (foe/wire/foe.hpp, ETG.1000.6 §5.8).
#include "foe/wire/foe.hpp"
