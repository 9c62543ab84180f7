"""orientviz.viewer"""
