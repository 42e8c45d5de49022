/* fmu_state_ref.h — the serialized FMU state format as docs/fmu.md documents it, written
 * out independently of the glue (fmu/glue/fmu_common.c), for the C tests that damage
 * and craft states: the header layout and the IEEE 802.3 CRC-32 (reflected polynomial
 * 0xEDB88320, initial value and final xor 0xFFFFFFFF) from its bitwise definition, a
 * byte at a time through a 256-entry table built here at run time from that definition
 * (the glue's table is made by the compiler). ref_crc32_check() compares it with the
 * standard's check value. */
#ifndef FMU_STATE_REF_H
#define FMU_STATE_REF_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#define REF_STATE_HEADER_SIZE 72 /* magic 8, format 4, size 4, CRC-32 4, reserved 4, token 48 */
#define REF_STATE_FORMAT_AT 8
#define REF_STATE_CRC_AT 16

static inline uint32_t ref_crc32(const uint8_t *p, size_t n)
{
    static uint32_t table[256]; /* the CRC register after 8 shifts of each byte value */
    static int built = 0;
    if (!built) {
        for (uint32_t v = 0; v < 256; ++v) {
            uint32_t c = v;
            for (int b = 0; b < 8; ++b)
                c = (c & 1u) ? (c >> 1) ^ 0xEDB88320u : c >> 1;
            table[v] = c;
        }
        built = 1;
    }
    uint32_t crc = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; ++i)
        crc = (crc >> 8) ^ table[(crc ^ p[i]) & 0xFFu];
    return crc ^ 0xFFFFFFFFu;
}

/* The standard's check value: CRC-32 of the ASCII digits "123456789" is 0xCBF43926. */
static inline int ref_crc32_check(void)
{
    return ref_crc32((const uint8_t *)"123456789", 9) == 0xCBF43926u;
}

/* The CRC-32 field of a serialized state as the bytes after the header make it: what a
 * crafted file carries. */
static inline void ref_state_fix_crc(uint8_t *bytes, size_t size)
{
    const uint32_t crc = ref_crc32(bytes + REF_STATE_HEADER_SIZE, size - REF_STATE_HEADER_SIZE);
    memcpy(bytes + REF_STATE_CRC_AT, &crc, sizeof crc);
}

static inline uint32_t ref_state_crc(const uint8_t *bytes)
{
    uint32_t crc;
    memcpy(&crc, bytes + REF_STATE_CRC_AT, sizeof crc);
    return crc;
}

#endif /* FMU_STATE_REF_H */
