//! Integration tests of the contact laws (1-D impacts, friction, adhesion, energy).
