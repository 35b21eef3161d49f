"""An independent check of a VCB run's closing: the mechanism rebuilt as a planar multibody
model (rigid bodies, revolute joints, a unilateral compliant cam-roller contact) in Exudyn,
an open multibody engine installed with the optional extra ``camopt[multibody]``, and its
closing compared with camopt's lumped dynamics (``camopt verify``, docs/verify.md)."""
