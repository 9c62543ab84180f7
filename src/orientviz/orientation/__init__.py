"""orientviz.orientation"""
