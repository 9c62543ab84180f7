"""orientviz.radar"""
