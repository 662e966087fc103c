//! Ocean height-field model (paper section 2, eqs. 1-7): being built in the ocean issue.
