#pragma once
// The techniques, once: X(name, Params) per technique, in the order of the Technique enum, CLI
// choices and reports. Adding a technique is one line here and one techniques/<name>.{h,cpp}
// (its parameters, table and registry entry) plus one shaders/shadow_<name>.glsl; see
// docs/renderer.md, "Adding a technique".
#include <penumbra/shadows/techniques/edtsm.h>
#include <penumbra/shadows/techniques/edtssm.h>
#include <penumbra/shadows/techniques/erosion.h>
#include <penumbra/shadows/techniques/esm.h>
#include <penumbra/shadows/techniques/evsm.h>
#include <penumbra/shadows/techniques/hard.h>
#include <penumbra/shadows/techniques/msm.h>
#include <penumbra/shadows/techniques/pcf.h>
#include <penumbra/shadows/techniques/pcss.h>
#include <penumbra/shadows/techniques/rbsm.h>
#include <penumbra/shadows/techniques/rpcf.h>
#include <penumbra/shadows/techniques/vsm.h>

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
