//! Closing the loop: compare a model with measured hysteresis, find and add the missing effect.
