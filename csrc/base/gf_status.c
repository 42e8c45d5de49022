#include "base/gf_status.h"

const char *gf_status_string(gf_status status)
{
    switch (status) {
    case GF_OK: return "ok";
    case GF_ERR_NULL_POINTER: return "a required pointer argument is NULL";
    case GF_ERR_NONFINITE_INPUT: return "an input sample is not finite (NaN or Inf)";
    case GF_ERR_BAD_PARAMETER: return "a parameter is out of its legal range";
    case GF_ERR_SINGULAR_GEOMETRY: return "the sensor geometry is singular";
    case GF_ERR_BAD_SIZE: return "an array size is zero or exceeds the fixed maximum";
    case GF_ERR_OUT_OF_RANGE: return "a sample is beyond the stated physical limit";
    case GF_ERR_BAD_TIME: return "sample times are not strictly increasing";
    case GF_ERR_DIVERGED: return "the navigation state left its domain (pole, absurd height)";
    case GF_ERR_BAD_TEXT: return "a line of text is not a row of numbers of the expected width";
    }
    return "unknown status code";
}
