"""Operating points used to check the converter library against the CCM/DCM closed forms.

(converter, parameters, expected mode); C is raised where the ripple would bias the CCM mean
beyond the 0.05 % check (the small-ripple formulas ignore it).
"""
OPERATING_POINTS = [
    ("buck", {"L": "100u"}, "CCM"),
    ("buck", {"D": 0.7, "L": "50u", "R": 5}, "CCM"),
    ("buck", {}, "DCM"),
    ("buck", {"D": 0.2, "L": "5u", "R": 20}, "DCM"),
    ("boost", {"L": "100u", "R": 20, "C": "470u"}, "CCM"),
    ("boost", {"D": 0.6, "L": "200u", "C": "470u"}, "CCM"),
    ("boost", {"D": 0.3, "R": 50}, "DCM"),
    ("buck-boost", {"L": "100u", "C": "470u"}, "CCM"),
    ("buck-boost", {"D": 0.6, "L": "200u", "C": "470u"}, "CCM"),
    ("buck-boost", {}, "DCM"),
    ("buck-boost", {"D": 0.25, "L": "5u", "R": 20}, "DCM"),
    ("cuk", {"C2": "470u"}, "CCM"),
    ("cuk", {"D": 0.6, "L1": "200u", "L2": "200u", "C2": "470u"}, "CCM"),
    ("cuk", {"L1": "10u", "L2": "10u"}, "DCM"),
    ("cuk", {"D": 0.3, "L1": "20u", "L2": "5u"}, "DCM"),
]
#: Relative tolerance of the steady-state mean output against the closed form, per mode.
TOLERANCE = {"CCM": 5e-4, "DCM": 1e-2}
