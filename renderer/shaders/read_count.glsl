// Counting a shading pass's shadow reads (Renderer::count_shading_reads): compiled with
// COUNT_SHADOW_READS, every texture read of a shadow lookup is wrapped in COUNTED(texels,
// bytes_per_texel, read), which tallies one texture instruction, the texels it touches (a gather or
// a bilinear fetch: 4; a nearest fetch or comparison: 1) and their bytes for the pixel; the
// shading pass adds the pixel's tally to the ShadowReadsResult buffer (shadow_contract.h) once.
// Without the define COUNTED is the read alone. Bytes are the texture's storage per texel, read
// as if no cache held them: what a GPU's texture units fetch, not what its memory delivers.
#ifndef READ_COUNT_GLSL
#define READ_COUNT_GLSL
#if defined(COUNT_SHADOW_READS)
uniform int u_count_moment_bytes;  // bytes per texel of the filtered moments (their MomentsFormat)
uint g_read_instructions = 0u;
uint g_read_texels = 0u;
uint g_read_bytes = 0u;
int count_read(int texels, int bytes_per_texel) {
  g_read_instructions += 1u;
  g_read_texels += uint(texels);
  g_read_bytes += uint(texels * bytes_per_texel);
  return 0;
}
#define COUNTED(texels, bytes_per_texel, read) (count_read(texels, bytes_per_texel), read)
#else
#define COUNTED(texels, bytes_per_texel, read) (read)
#endif
#endif
