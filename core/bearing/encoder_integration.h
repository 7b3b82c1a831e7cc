// Moved to core/timing (both problems integrate encoders at latent times); kept for the bearing
// code.
#include <calib/core/timing/encoder_integration.h>  // IWYU pragma: export
