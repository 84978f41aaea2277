#pragma once
// The techniques, once: X(name, Params) per technique, in the order of the Technique enum, CLI
// choices and reports. Adding a technique is one line here and one techniques/<name>.{h,cpp}
// (its parameters, table and registry entry) plus one shaders/shadow_<name>.glsl; see
// docs/renderer.md, "Adding a technique".
#include "shadows/techniques/edtsm.h"
#include "shadows/techniques/edtssm.h"
#include "shadows/techniques/erosion.h"
#include "shadows/techniques/esm.h"
#include "shadows/techniques/evsm.h"
#include "shadows/techniques/hard.h"
#include "shadows/techniques/msm.h"
#include "shadows/techniques/pcf.h"
#include "shadows/techniques/pcss.h"
#include "shadows/techniques/rbsm.h"
#include "shadows/techniques/rpcf.h"
#include "shadows/techniques/vsm.h"

#define PENUMBRA_TECHNIQUES(X) \
  X(hard, NoParams)            \
  X(pcf, PcfParams)            \
  X(pcss, PcssParams)          \
  X(vsm, VsmParams)            \
  X(edtsm, EdtsmParams)        \
  X(edtssm, EdtssmParams)      \
  X(erosion, ErosionParams)    \
  X(rbsm, RbsmParams)          \
  X(rpcf, RpcfParams)          \
  X(msm, MsmParams)            \
  X(evsm, EvsmParams)          \
  X(esm, EsmParams)
