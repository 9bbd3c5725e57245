//! (to be written) ContactModel, NormalLaw, FrictionLaw, RollingResistance, DmtAdhesion.
