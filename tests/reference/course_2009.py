"""Course answer for ../shared/course-data/ensayo.mat (FreeMat data of 2009).

Provenance: docs/conventions.md ("The sensor model"), which records the course answer; the same
estimates appear in ../shared/references/course-report-WLS.txt, section 2.1.2
(x̂ = [-0.0301, 0.0767, 0.0100, -0.0175]). Model A_m = (1 + scale)·A_r + bias + v with
σ² = 0.25 (x), 0.64 (y). Values are given to 4 decimals (estimates) and 5 significant digits
(variances); tests assert |est - ref| <= 0.5·10^-d for the digits given.
"""

NOISE_VAR = (0.25, 0.64)

ESTIMATES = {  # value, decimals given
    "scale_x": (-0.0301, 4),
    "bias_x": (0.0767, 4),
    "scale_y": (0.0100, 4),
    "bias_y": (-0.0175, 4),
}

VARIANCES = {  # value, significant digits given
    "scale_x": (2.6031e-07, 5),
    "bias_x": (1.2499e-05, 5),
    "scale_y": (6.6632e-07, 5),
    "bias_y": (3.1998e-05, 5),
}
