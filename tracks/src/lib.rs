//! TRACKS: weak-form tracking of a coarse guide animation (Bergou et al. 2007).
