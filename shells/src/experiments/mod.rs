//! The experiments of `shells` (STYLE.md): each module holds one scene family's parameters (the
//! RON `params` block), its run and its typed report; `protocol` is the run loop they share.

pub mod contact;
pub mod protocol;
