"""Why some corpus files that their own tool accepts are rejected by cosleec.

Each entry is a real defect of that file (sleec-language.md §11), with the error codes
cosleec reports. Anything else that its own tool accepts must check clean.
"""

from __future__ import annotations

CROSS_SCALE = (
    "compares a measure with a literal of another scale (LEGOS' global literal table hides it, §11.8)"
)
DUP_RULE = "two rules share a name (§11.17)"
DUP_PURPOSE = "two purposes share a name (§5)"
BSN = (
    CROSS_SCALE + "; `{riskLevel} > autonomyConcern` compares a scale with a number; purpose P6's "
    "unbraced `riskLevel` in a comparison is LEGOS syntax too (§11.9)"
)

REJECTED: dict[str, tuple[frozenset[str], str]] = {
    "UoY-RoboStar__SLEEC-TK__sleec-core__CaseStudies__DAISY.sleec": (
        frozenset({"undeclared-event"}),
        "Rule6's trigger UserRequestInfo (and two responses) are not declared",
    ),
    "Julian-Moncarz__ASP_project__real_sleec_files__SafeSCAD.sleec": (
        frozenset({"scale-literal"}),
        CROSS_SCALE,
    ),
    "Julian-Moncarz__ASP_project__sleec_files__case_studies__DressAssist.sleec": (
        frozenset({"duplicate-rule"}),
        DUP_RULE,
    ),
    "LailaMahmoud__SLEEC_PATCH__results__ASPEN__ASPEN_SLEECPATCH.sleec": (
        frozenset({"scale-literal"}),
        CROSS_SCALE,
    ),
    "NickF0211__LEGOS-SLEEC__ASPEN__aspen-corrected.sleec": (frozenset({"scale-literal"}), CROSS_SCALE),
    "NickF0211__LEGOS-SLEEC__ASPEN__aspen.sleec": (frozenset({"scale-literal"}), CROSS_SCALE),
    "NickF0211__LEGOS-SLEEC__BSN__BSN-corrected.sleec": (frozenset({"scale-literal", "type"}), BSN),
    "NickF0211__LEGOS-SLEEC__BSN__BSN.sleec": (frozenset({"scale-literal", "type"}), BSN),
    "NickF0211__LEGOS-SLEEC__dressingAssist__DRESSASSIST-corrected.sleec": (
        frozenset({"duplicate-rule"}),
        DUP_RULE,
    ),
    "NickF0211__LEGOS-SLEEC__dressingAssist__DRESSASSIST.sleec": (frozenset({"duplicate-rule"}), DUP_RULE),
    "NickF0211__LEGOS-SLEEC__gdpr__DPA-corrected.sleec": (frozenset({"duplicate-name"}), DUP_PURPOSE),
    "NickF0211__LEGOS-SLEEC__gdpr__DPA.sleec": (frozenset({"duplicate-name"}), DUP_PURPOSE),
    "NickF0211__LEGOS-SLEEC__safescade__safescade-corrected.sleec": (
        frozenset({"duplicate-rule", "scale-literal"}),
        "R7_1 twice; " + CROSS_SCALE,
    ),
    "NickF0211__LEGOS-SLEEC__safescade__safescade.sleec": (frozenset({"scale-literal"}), CROSS_SCALE),
    "NickF0211__sleecvalDef__EVALUATION__RQ2__RAINCOAT-Elicitation-Validation__CASPER__casper-RAINCOAT-corrected.sleec": (
        frozenset({"scale-literal"}),
        CROSS_SCALE,
    ),
    "NickF0211__sleecvalDef__EVALUATION__RQ2__RAINCOAT-Elicitation-Validation__CASPER__casper-RAINCOAT.sleec": (
        frozenset({"duplicate-rule", "scale-literal"}),
        "Rule23 twice; " + CROSS_SCALE,
    ),
    "NickF0211__sleecvalDef__EVALUATION__RQ2__RAINCOAT-Elicitation-Validation__TABIAT__TABIAT-RAINCOAT.sleec": (
        frozenset({"duplicate-name"}),
        DUP_PURPOSE,
    ),
    "NickF0211__sleecvalDef__LEGO_SLEEC__SleecFrontEnd__dressingAssist__DRESSASSIST-corrected_san.sleec": (
        frozenset({"duplicate-rule"}),
        DUP_RULE,
    ),
    "NickF0211__sleecvalDef__LEGO_SLEEC__SleecFrontEnd__gdpr__DPA-corrected.sleec": (
        frozenset({"duplicate-name"}),
        DUP_PURPOSE,
    ),
    "a-l-partis__SLEEC-ADAPT__CaseStudies__Chatbot__Chatbot-UniversalRules.sleec": (
        frozenset({"duplicate-rule"}),
        "Rule1 twice (" + DUP_RULE + ")",
    ),
    "a-l-partis__SLEEC-ADAPT__CaseStudies__RobotVacuum__RobotVacuum-ReligiousUser.sleec": (
        frozenset({"undeclared-event"}),
        "response SetSilentCleaningMode is not declared",
    ),
}
