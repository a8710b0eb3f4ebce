//! Environments for rays that leave the scene (paper 001): filled in by the environment work.
