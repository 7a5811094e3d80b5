//! Automatic rigging: skeleton embedding and bone-heat skin weights (Baran and Popovic 2007).
