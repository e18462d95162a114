//! The content-addressed cache of finished renders (not yet).
