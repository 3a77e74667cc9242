"""The paper's 40-step evaluation: Tables 1-3 computed and set beside the paper's (``tables``),
its friction three ways (``friction``), and the report with plots (``report``)."""
