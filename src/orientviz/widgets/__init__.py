"""orientviz.widgets"""
