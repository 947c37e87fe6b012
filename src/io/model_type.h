// Deprecated: ModelType, ModelRegistry and the built-in types are declared in
// <pc_ekf/model/model_type.h>. This header forwards there so that plugins
// written against the old path still build; include the new one instead.
#pragma once

#include "pc_ekf/model/model_type.h"
