/* gf_status.h — status codes returned by every gfins_fmi C entry point.
 *
 * Every public function returns a gf_status. GF_OK is 0; every other value is an
 * error that left the caller's state unchanged unless the function documents
 * otherwise (batch entries report how many samples were processed before it).
 */
#ifndef GF_STATUS_H
#define GF_STATUS_H

#ifdef __cplusplus
extern "C" {
#endif

/* CDEF BEGIN */
typedef enum gf_status {
    GF_OK = 0,
    GF_ERR_NULL_POINTER = 1,     /* a required pointer argument was NULL */
    GF_ERR_NONFINITE_INPUT = 2,  /* a sample contained NaN or +-Inf */
    GF_ERR_BAD_PARAMETER = 3,    /* a parameter is out of its physical/legal range */
    GF_ERR_SINGULAR_GEOMETRY = 4,/* a sensor geometry cannot be used (zero axis, ...) */
    GF_ERR_BAD_SIZE = 5,         /* an array size is zero or above a fixed maximum */
    GF_ERR_OUT_OF_RANGE = 6,     /* a sample is beyond a stated physical limit */
    GF_ERR_BAD_TIME = 7,         /* sample times are not strictly increasing */
    GF_ERR_DIVERGED = 8,         /* the state left its domain (pole reached, absurd height) */
    GF_ERR_BAD_TEXT = 9          /* a line of text is not a row of numbers of the expected width */
} gf_status;

/* A static, human-readable description of a status code (never NULL). */
const char *gf_status_string(gf_status status);
/* CDEF END */

#ifdef __cplusplus
}
#endif

#endif /* GF_STATUS_H */
