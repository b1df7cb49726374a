"""The paper's published figures (Wang & Luo, Biomimetics 10(7):446, 2025), for the columns of
RESULTS.md labelled "paper, real TUM".

Transcribed from the article's Tables 2 to 6 and its text. Every TUM value is measured by the paper
on the real TUM RGB-D fr3 sequences, on its own hardware; "ours" is the paper's system (Y+M+K).
None stands for a value the paper does not give.
"""
from __future__ import annotations

# Table 2: ATE RMSE [m] on the fr3 walking sequences.
ATE_RMSE_M = {
    "walking_xyz": {"ORB-SLAM2": 0.7615, "ours": 0.0148},
    "walking_halfsphere": {"ORB-SLAM2": 0.6215, "ours": 0.0243},
    "walking_rpy": {"ORB-SLAM2": 0.8545, "ours": 0.0320},
    "walking_static": {"ORB-SLAM2": 0.3340, "ours": 0.0078},
}

# Table 2's low-dynamic sitting_xyz row lost a cell when the article's text was extracted, so its
# columns cannot be told apart: the values in their printed order, for a footnote only.
SITTING_XYZ_PRINTED_ATE_M = (0.0091, 0.0159, 0.0148, 0.0109, 0.0117, 0.0111)

# Table 3: RPE RMSE [m] (the paper's time step is not stated).
RPE_RMSE_M = {
    "walking_xyz": {"ORB-SLAM2": 0.3884, "ours": 0.0189},
    "walking_halfsphere": {"ORB-SLAM2": 0.3772, "ours": 0.0250},
    "walking_rpy": {"ORB-SLAM2": 0.3838, "ours": 0.0410},
    "walking_static": {"ORB-SLAM2": 0.2056, "ours": 0.0106},
}

# Table 4 (ablation): ATE (RMSE, standard deviation) [m] per system. Y = masks only, YM = masks and
# MAD of depth, YMK = plus the keyframe selector. The paper has no run without dynamic handling
# other than ORB-SLAM2 itself.
ABLATION_ATE_M = {
    "walking_xyz": {"ORB-SLAM2": (0.7615, 0.4255), "Y": (0.0159, 0.0080), "YM": (0.0153, 0.0075),
                    "YMK": (0.0148, 0.0075)},
    "walking_halfsphere": {"ORB-SLAM2": (0.6215, 0.3134), "Y": (0.0274, 0.0123), "YM": (0.0262, 0.0123),
                           "YMK": (0.0243, 0.0122)},
    "walking_rpy": {"ORB-SLAM2": (0.8545, 0.4393), "Y": (0.0436, 0.0303), "YM": (0.0359, 0.0191),
                    "YMK": (0.0320, 0.0196)},
    "walking_static": {"ORB-SLAM2": (0.3340, 0.1444), "Y": (0.0091, 0.0041), "YM": (0.0087, 0.0044),
                       "YMK": (0.0078, 0.0033)},
}

# Headlines of the text: ATE 97.01 % and RPE 93.16 % lower than ORB-SLAM2, on average over the
# four walking sequences.
ATE_REDUCTION_MEAN = 0.9701
RPE_REDUCTION_MEAN = 0.9316

# Figure 10 and its text: Y+M+K keeps this fraction fewer keyframes than ORB-SLAM2.
KEYFRAME_REDUCTION = {"walking_xyz": 0.6932, "walking_halfsphere": 0.4917, "walking_rpy": 0.6349,
                      "walking_static": 0.6285}
KEYFRAME_REDUCTION_MEAN = 0.6120

# Table 5: milliseconds per frame on the paper's laptop (i5-12500H; the network on an RTX 3050).
TIME_MS = {"ORB-SLAM2": {"segmentation": None, "tracking": 22.8602},
           "ours": {"segmentation": 25.28, "tracking": 26.7219}}

# Table 6: loop closure on the paper's robot, 8 laps with one loop each: (TP, FP, FN, precision,
# recall). The printed recall of BoW in the dynamic scene is 62.50 %, its TP and FN give 75 %.
LOOPS = {
    "loop_dynamic": {"bow_only": (6, 0, 2, 1.0, 0.75), "cge": (8, 0, 0, 1.0, 1.0)},
    "loop_structure_change": {"bow_only": (7, 0, 1, 1.0, 0.875), "cge": (8, 0, 0, 1.0, 1.0)},
}
LOOP_SCENE_NAMES = {"loop_dynamic": "dynamic interference (a person walks in view)",
                    "loop_structure_change": "structural change (two chairs, a laptop, an umbrella added)"}
