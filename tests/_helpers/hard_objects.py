"""Objects of the grip populations that once broke the simulator or the fit, shared by the tests
that keep them working."""

from __future__ import annotations

from deformctl.sim import ObjectSpec

#: population --grip --laws kv=1,hc=1,sls=1 -n 1500 --seed 1, object P1224: W 1.28 N, F_w 0.65 N,
#: D 30.05 N/cm at F_w, n 2.92, compression at F_w 0.02 cm. A squeeze to 1 % strain goes to
#: 500 F_w, where the law's tangent is 60 times the one at F_w.
P1224 = ObjectSpec(
    "P1224",
    (18.266157255740307, 18.86999851884091, 13.783762496895122),
    1.2823604904060122,
    0.9791332774328168,
    30.04844412194788,
    0.03169091107723927,
    2.923045909747441,
)
