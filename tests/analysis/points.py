"""The exact operating points of the accuracy tests (buck, boost, buck-boost, Cuk; CCM, DCM with a conduction
interval of 0.37 % of T, GDCM-ON, GDCM-OFF, loads to 10 kOhm, 10 kHz to 1 MHz, duty 0.05 to 0.95), shared by the
tests that compare against them."""

POINTS = {
    "buck-ccm": ("buck", {"D": 0.5, "L": "100u", "R": 5}),
    "buck-dcm": ("buck", {}),
    "buck-dcm-0.37%": ("buck", {"D": 0.05, "L": "10u", "R": "10k"}),        # conduction 0.0037 T
    "buck-1MHz": ("buck", {"D": 0.3, "L": "2u", "R": 5, "f_sw": "1meg"}),
    "buck-D0.95-10kHz": ("buck", {"D": 0.95, "L": "1m", "R": 10, "C": "470u", "f_sw": "10k"}),
    "boost-ccm": ("boost", {"D": 0.5, "L": "100u", "R": 20, "C": "470u"}),
    "boost-dcm-10k": ("boost", {"D": 0.3, "L": "10u", "R": "10k"}),
    "boost-dcm": ("boost", {"D": 0.3, "R": 50}),
    "buck-boost-dcm-5k": ("buck-boost", {"D": 0.7, "L": "22u", "R": "5k", "f_sw": "250k"}),
    "buck-boost-ccm": ("buck-boost", {"D": 0.4, "L": "100u", "R": 10}),
    "buck-boost-10kHz": ("buck-boost", {"D": 0.5, "L": "1m", "R": 20, "f_sw": "10k"}),
    "cuk-ccm": ("cuk", {"C2": "470u"}),
    "cuk-gdcm-off": ("cuk", {"L1": "10u", "L2": "10u"}),
    "cuk-gdcm-on": ("cuk", {"D": 0.5, "C1": "130n"}),
    "cuk-D0.95": ("cuk", {"D": 0.95, "L1": "1m", "L2": "1m", "R": 5}),
}
