// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.revrobotics.spark.config;
public class SparkMaxConfig extends SparkBaseConfig {}
